#include <array>
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "crowdslam/map/keyframe.h"
#include "crowdslam/map/map.h"
#include "crowdslam/map/map_point.h"

using namespace crowdslam;
using namespace crowdslam::map;

namespace {

std::shared_ptr<geometry::PinholeCamera> test_camera() {
  auto cam = std::make_shared<geometry::PinholeCamera>();
  cam->fx = cam->fy = 500;
  cam->cx = 320;
  cam->cy = 240;
  cam->width = 640;
  cam->height = 480;
  cam->bf = 40;
  return cam;
}

// Features with n keypoints on a grid, random descriptors, optional depth on even indices.
std::shared_ptr<FrameFeatures> make_features(size_t n, unsigned seed) {
  auto f = std::make_shared<FrameFeatures>();
  std::mt19937 rng(seed);
  f->descriptors = cv::Mat(static_cast<int>(n), 32, CV_8UC1);
  for (size_t i = 0; i < n; ++i) {
    cv::KeyPoint kp(cv::Point2f(10.0f + 7.0f * (i % 80), 10.0f + 7.0f * (i / 80)), 31.0f, 0, 1,
                    static_cast<int>(i % 3));
    f->keys.push_back(kp);
    f->keys_un.push_back(kp);
    f->depth_m.push_back(i % 2 == 0 ? 2.0f : -1.0f);
    f->right_u.push_back(i % 2 == 0 ? kp.pt.x - 20.0f : -1.0f);
    for (int b = 0; b < 32; ++b)
      f->descriptors.at<uint8_t>(static_cast<int>(i), b) = static_cast<uint8_t>(rng());
  }
  f->grid = FeatureGrid(f->keys_un, geometry::ImageBounds{0, 640, 0, 480});
  return f;
}

struct TestMap {
  Map map;
  std::shared_ptr<geometry::PinholeCamera> camera = test_camera();
  std::shared_ptr<ScaleLevels> levels = std::make_shared<ScaleLevels>(1.2f, 8);

  std::shared_ptr<KeyFrame> add_keyframe(size_t n_features = 200) {
    const uint64_t id = map.next_keyframe_id();
    geometry::Vec6 twist = geometry::Vec6::Zero();
    twist(0) = 0.1 * static_cast<double>(id);
    auto kf = std::make_shared<KeyFrame>(id, id * 3, 1.0 + id, camera, levels,
                                         make_features(n_features, static_cast<unsigned>(id + 1)),
                                         geometry::SE3::exp(twist));
    map.add_keyframe(kf);
    return kf;
  }
  // A point seen by the given keyframes at keypoint `index` in each.
  std::shared_ptr<MapPoint> add_point(const std::vector<std::shared_ptr<KeyFrame>>& kfs, size_t index) {
    auto p = std::make_shared<MapPoint>(map.next_map_point_id(), geometry::Vec3(0, 0, 2), kfs.front(), 0);
    for (const auto& kf : kfs) {
      kf->add_map_point(index, p);
      p->add_observation(kf, index);
    }
    map.add_map_point(p);
    return p;
  }
};

}  // namespace

TEST(FeatureGrid, AreaQueryMatchesBruteForce) {
  const auto f = make_features(1000, 7);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> ux(0, 640), uy(0, 480), ur(1, 60);
  for (int trial = 0; trial < 200; ++trial) {
    const float x = ux(rng), y = uy(rng), r = ur(rng);
    auto got = f->grid.features_in_area(f->keys_un, x, y, r, 1, 2);
    std::sort(got.begin(), got.end());
    std::vector<size_t> expected;
    for (size_t i = 0; i < f->size(); ++i) {
      const auto& kp = f->keys_un[i];
      if (kp.octave >= 1 && kp.octave <= 2 && std::abs(kp.pt.x - x) < r && std::abs(kp.pt.y - y) < r)
        expected.push_back(i);
    }
    ASSERT_EQ(got, expected) << "query " << x << "," << y << " r=" << r;
  }
}

TEST(ScaleLevels, GeometricSeries) {
  const ScaleLevels levels(1.2f, 8);
  EXPECT_FLOAT_EQ(levels.scale[0], 1.0f);
  EXPECT_NEAR(levels.scale[7], std::pow(1.2, 7), 1e-4);
  EXPECT_NEAR(levels.inv_sigma2[3], 1.0 / std::pow(1.2, 6), 1e-6);
}

TEST(Covisibility, WeightsCountSharedPointsAndThresholdApplies) {
  TestMap t;
  auto a = t.add_keyframe(), b = t.add_keyframe(), c = t.add_keyframe();
  for (size_t i = 0; i < 20; ++i) t.add_point({a, b}, i);   // a-b share 20
  for (size_t i = 20; i < 25; ++i) t.add_point({a, c}, i);  // a-c share 5 (< 15)
  for (size_t i = 30; i < 60; ++i) t.add_point({b, c}, i);  // b-c share 30
  a->update_connections();
  EXPECT_EQ(a->weight(b->id), 20);
  EXPECT_EQ(a->weight(c->id), 0);  // below threshold, and a strong edge exists
  EXPECT_EQ(b->weight(a->id), 20);
  c->update_connections();
  ASSERT_EQ(c->best_covisible(1).size(), 1u);
  EXPECT_EQ(c->best_covisible(1)[0]->id, b->id);
  EXPECT_EQ(c->weight(b->id), 30);
  EXPECT_EQ(c->covisible_by_weight(25).size(), 1u);
}

TEST(Covisibility, WeakOnlyNeighbourStillConnected) {
  TestMap t;
  auto a = t.add_keyframe(), b = t.add_keyframe();
  for (size_t i = 0; i < 4; ++i) t.add_point({a, b}, i);
  b->update_connections();
  EXPECT_EQ(b->weight(a->id), 4);
  EXPECT_EQ(b->parent()->id, a->id);
}

TEST(MapPoint, MotionScoreCountsMovingVerdictsAmongTheLastEight) {
  map::MapPoint p(0, geometry::Vec3(0, 0, 1), nullptr, 0);
  EXPECT_EQ(p.motion_score(), 0);
  // A static point judged moving once in every four observations, for a long time: never above 2.
  int highest = 0;
  for (int k = 0; k < 200; ++k) highest = std::max(highest, p.record_motion(k % 4 == 0));
  EXPECT_EQ(highest, 2);
  // A point that starts to move: one more moving verdict per observation until all 8 are.
  std::vector<int> scores;
  for (int k = 0; k < 9; ++k) scores.push_back(p.record_motion(true));
  EXPECT_EQ(scores.back(), 8);
  EXPECT_EQ(p.record_motion(true), 8);  // at most the window
  // And stops: each static verdict pushes one moving verdict out.
  for (int k = 1; k <= 8; ++k) EXPECT_EQ(p.record_motion(false), 8 - k);
}

TEST(MapPoint, StereoObservationsCountTwiceAndPointDiesWithFewObservations) {
  TestMap t;
  auto a = t.add_keyframe(), b = t.add_keyframe(), c = t.add_keyframe();
  auto p = t.add_point({a, b, c}, 1);  // index 1: monocular observations
  EXPECT_EQ(p->num_observations(), 3);
  auto q = t.add_point({a, b}, 2);  // index 2: has depth -> counts twice
  EXPECT_EQ(q->num_observations(), 4);
  p->erase_observation(a->id);  // 2 left -> bad
  EXPECT_TRUE(p->is_bad());
  EXPECT_EQ(b->map_point(1), nullptr);
  EXPECT_EQ(t.map.erase_bad_map_points(), 1u);
  EXPECT_EQ(t.map.num_map_points(), 1u);
}

TEST(KeyFrame, FoundMapPointsCountsFramesNotKeyframes) {
  // The RGB-D / stereo keyframe policy's reference count: points matched by tracking in >= n frames,
  // whatever number of keyframes observes them (tracked_map_points counts keyframe observations).
  TestMap t;
  auto a = t.add_keyframe(), b = t.add_keyframe();
  auto seen_once = t.add_point({a}, 1);    // found 1 (its creation), 1 keyframe
  auto found_often = t.add_point({a}, 3);  // 1 keyframe, but tracked in 4 more frames
  found_often->increase_found(4);
  auto two_keyframes = t.add_point({a, b}, 5);  // 2 keyframes, never tracked since
  auto bad = t.add_point({a}, 7);
  bad->increase_found(9);
  bad->set_bad();
  EXPECT_EQ(seen_once->found_count(), 1);
  EXPECT_EQ(a->found_map_points(1), 3);
  EXPECT_EQ(a->found_map_points(3), 1);  // found_often only; the bad point never counts
  EXPECT_EQ(a->found_map_points(6), 0);
  EXPECT_EQ(a->tracked_map_points(2), 1);  // two_keyframes: the observation count tells another story
  EXPECT_EQ(b->found_map_points(2), 0);
}

// Four keyframes whose keypoint 5 has an all-zero descriptor, and their features to write it through.
struct DescriptorKeyframes {
  std::vector<std::shared_ptr<KeyFrame>> kfs;
  std::vector<std::shared_ptr<FrameFeatures>> f;
  explicit DescriptorKeyframes(TestMap& t) {
    for (int i = 0; i < 4; ++i) {
      kfs.push_back(t.add_keyframe());
      f.push_back(std::const_pointer_cast<FrameFeatures>(kfs.back()->features));
      f.back()->descriptors.row(5).setTo(0);
    }
  }
};

TEST(MapPoint, DistinctiveDescriptorIsTheMedoid) {
  TestMap t;
  auto [kfs, f] = DescriptorKeyframes(t);
  // Descriptors at index 5: a = 0, b = byte0 set (8 bits), c = bytes 0,1 (16), d = byte0 + one bit of byte2.
  // Pairwise: ab 8, ac 16, ad 9, bc 8, bd 1, cd 9. Median (with self, index (n-1)/2) per row:
  // a 8, b 1, c 8, d 1 -> b (first of the tie) is the distinctive descriptor.
  f[1]->descriptors.at<uint8_t>(5, 0) = 0xFF;
  f[2]->descriptors.at<uint8_t>(5, 0) = 0xFF;
  f[2]->descriptors.at<uint8_t>(5, 1) = 0xFF;
  f[3]->descriptors.at<uint8_t>(5, 0) = 0xFF;
  f[3]->descriptors.at<uint8_t>(5, 2) = 0x01;
  auto p = t.add_point(kfs, 5);
  p->compute_distinctive_descriptor();
  const Descriptor d = p->descriptor();
  EXPECT_EQ(d[0], 0xFF);
  EXPECT_EQ(d[1], 0x00);
  EXPECT_EQ(d[2], 0x00);
}

TEST(MapPoint, DistinctiveDescriptorFollowsItsObservations) {
  // Computed once per set of observations (MapPoint::compute_distinctive_descriptor skips a repeat):
  // adding or erasing an observation, or setting the descriptor from outside, makes the next call count.
  TestMap t;
  auto [kfs, f] = DescriptorKeyframes(t);
  // a = 0, b = all ones, c = all ones but 4 bits, d = 0.
  f[1]->descriptors.row(5).setTo(0xFF);
  f[2]->descriptors.row(5).setTo(0xFF);
  f[2]->descriptors.at<uint8_t>(5, 0) = 0x0F;
  const auto [a, b, c, d] = std::tie(kfs[0], kfs[1], kfs[2], kfs[3]);
  auto p = t.add_point({a, b}, 5);
  p->compute_distinctive_descriptor();
  EXPECT_EQ(p->descriptor()[1], 0x00);  // a and b tie: the first, a
  p->add_observation(c, 5);
  p->compute_distinctive_descriptor();
  EXPECT_EQ(p->descriptor()[1], 0xFF);  // b: median distance 4 (to c)
  EXPECT_EQ(p->descriptor()[0], 0xFF);
  // Set from outside, then computed again from the same observations: the medoid comes back.
  const std::array<uint8_t, 32> zeros{};
  p->set_descriptor(zeros.data());
  EXPECT_EQ(p->descriptor()[1], 0x00);
  p->compute_distinctive_descriptor();
  EXPECT_EQ(p->descriptor()[1], 0xFF);
  p->add_observation(d, 5);
  p->compute_distinctive_descriptor();
  EXPECT_EQ(p->descriptor()[1], 0x00);  // a: median distance 0 (to d)
  p->erase_observation(d->id);
  ASSERT_FALSE(p->is_bad());
  p->compute_distinctive_descriptor();
  EXPECT_EQ(p->descriptor()[1], 0xFF);  // b again
}

TEST(MapPoint, NormalAndScaleRange) {
  TestMap t;
  auto a = t.add_keyframe();  // camera centre at origin-ish, translation 0
  auto b = t.add_keyframe();
  auto p = t.add_point({a, b}, 3);  // octave 0 in a (3 % 3 == 0)
  p->set_world(a->camera_center() + geometry::Vec3(0, 0, 4));
  p->update_normal_and_depth();
  EXPECT_NEAR(p->normal().norm(), 1.0, 1e-9);
  // Level-0 observation at 4 m: max distance 4 * 1.2 (margin), min = 4 / 1.2^7 * 0.8.
  EXPECT_NEAR(p->max_distance(), 4.0 * 1.2, 1e-4);
  EXPECT_NEAR(p->min_distance(), 0.8 * 4.0 / std::pow(1.2, 7), 1e-4);
  EXPECT_EQ(p->predict_scale(4.0f, *t.levels), 0);
  EXPECT_EQ(p->predict_scale(4.0f / 1.2f / 1.2f, *t.levels), 2);
}

TEST(MapPoint, ViewGeometryIsTheSingleAccessorsUnderOneLock) {
  TestMap t;
  auto a = t.add_keyframe(), b = t.add_keyframe();
  auto p = t.add_point({a, b}, 3);
  p->set_world(a->camera_center() + geometry::Vec3(0.3, -0.2, 3.5));
  p->update_normal_and_depth();
  const MapPoint::ViewGeometry view = p->view_geometry();
  EXPECT_EQ(view.world, p->world());
  EXPECT_EQ(view.normal, p->normal());
  EXPECT_EQ(view.min_distance, p->min_distance());
  EXPECT_EQ(view.max_distance, p->max_distance());
  for (float d : {0.05f, 0.5f, 1.0f, 2.9f, 3.5f, 4.2f, 9.0f}) {
    EXPECT_EQ(view.predict_scale(d, *t.levels), p->predict_scale(d, *t.levels)) << d;
  }
}

TEST(MapPoint, ObservationsStayOrderedByKeyframeIdWhateverTheInsertionOrder) {
  TestMap t;
  std::vector<std::shared_ptr<KeyFrame>> kfs;
  for (int i = 0; i < 7; ++i) kfs.push_back(t.add_keyframe());
  auto p = std::make_shared<MapPoint>(t.map.next_map_point_id(), geometry::Vec3(0, 0, 2), kfs[3], 0);
  for (int i : {3, 6, 0, 5, 1, 4, 2}) p->add_observation(kfs[i], 10 + i);
  p->add_observation(kfs[5], 99);  // a second observation by the same keyframe is ignored
  EXPECT_EQ(p->index_in(kfs[5]->id), 15);
  p->erase_observation(kfs[4]->id);
  p->erase_observation(kfs[4]->id);  // erasing twice is harmless
  std::vector<uint64_t> visited;
  p->for_each_observation([&](uint64_t id, const MapPoint::Observation& o) {
    visited.push_back(id);
    EXPECT_EQ(o.index, 10 + id - kfs[0]->id);
  });
  EXPECT_EQ(visited,
            (std::vector<uint64_t>{kfs[0]->id, kfs[1]->id, kfs[2]->id, kfs[3]->id, kfs[5]->id, kfs[6]->id}));
  const auto copy = p->observations();
  ASSERT_EQ(copy.size(), 6u);
  EXPECT_TRUE(std::is_sorted(copy.begin(), copy.end(),
                             [](const auto& x, const auto& y) { return x.first < y.first; }));
  EXPECT_FALSE(p->is_observed_by(kfs[4]->id));
  EXPECT_EQ(p->index_in(kfs[4]->id), -1);
  EXPECT_TRUE(p->is_observed_by(kfs[6]->id));
  // The reference keyframe (kfs[3]) erased: the one with the smallest id takes over.
  p->erase_observation(kfs[3]->id);
  EXPECT_EQ(p->reference_keyframe(), kfs[0]);
}

TEST(MapPoint, MarksTellEachPassWhichPointsItHasSeen) {
  TestMap t;
  auto a = t.add_keyframe(), b = t.add_keyframe();
  auto p = t.add_point({a, b}, 1);
  auto q = t.add_point({a, b}, 2);
  const uint64_t first = MapPoint::next_mark();
  const uint64_t second = MapPoint::next_mark();
  EXPECT_NE(first, second);
  EXPECT_NE(first, 0u);  // a new point carries mark 0, which no pass has
  EXPECT_TRUE(p->mark(first));
  EXPECT_FALSE(p->mark(first));  // seen already in this pass
  EXPECT_TRUE(p->marked(first));
  EXPECT_FALSE(q->marked(first));
  EXPECT_TRUE(p->mark(second));  // a new pass starts afresh
  EXPECT_FALSE(p->marked(first));
  // A keyframe's points visited in place: each non-null slot once.
  size_t visited = 0;
  a->for_each_map_point([&](const std::shared_ptr<MapPoint>& point) {
    EXPECT_TRUE(point == p || point == q);
    ++visited;
  });
  EXPECT_EQ(visited, 2u);
  q->set_bad();
  EXPECT_EQ(a->valid_map_points(), (std::vector<std::shared_ptr<MapPoint>>{p}));
}

TEST(MapPoint, ReplaceMovesObservations) {
  TestMap t;
  auto a = t.add_keyframe(), b = t.add_keyframe(), c = t.add_keyframe();
  auto p = t.add_point({a, b}, 7);
  auto q = t.add_point({c}, 9);
  p->replace(q);
  EXPECT_TRUE(p->is_bad());
  EXPECT_EQ(p->replaced_by(), q);
  EXPECT_EQ(a->map_point(7), q);
  EXPECT_EQ(b->map_point(7), q);
  EXPECT_TRUE(q->is_observed_by(a->id));
  EXPECT_EQ(q->index_in(b->id), 7);
}

TEST(KeyFrame, CullingRepairsSpanningTreeAndUnlinks) {
  TestMap t;
  // Built incrementally, as tracking would: k1 attaches to k0; k2 shares most with k1; k3 with k1.
  size_t idx = 0;
  auto k0 = t.add_keyframe(), k1 = t.add_keyframe();
  for (int i = 0; i < 20; ++i) t.add_point({k0, k1}, idx++);
  k1->update_connections();
  auto k2 = t.add_keyframe();
  for (int i = 0; i < 30; ++i) t.add_point({k1, k2}, idx++);
  for (int i = 0; i < 18; ++i) t.add_point({k0, k2}, idx++);
  k2->update_connections();
  auto k3 = t.add_keyframe();
  for (int i = 0; i < 25; ++i) t.add_point({k1, k3}, idx++);
  for (int i = 0; i < 18; ++i) t.add_point({k2, k3}, idx++);
  k3->update_connections();
  ASSERT_EQ(k1->parent(), k0);
  ASSERT_EQ(k2->parent(), k1);
  ASSERT_EQ(k3->parent(), k1);

  k1->set_bad(t.map);
  EXPECT_TRUE(k1->is_bad());
  EXPECT_EQ(t.map.num_keyframes(), 3u);
  EXPECT_EQ(k0->weight(k1->id), 0);
  EXPECT_NE(k2->parent(), k1);
  EXPECT_NE(k3->parent(), k1);
  // Every remaining keyframe reaches the root through the tree.
  for (auto kf : {k2, k3}) {
    int steps = 0;
    auto node = kf;
    while (node->parent() && steps < 10) {
      node = node->parent();
      ++steps;
    }
    EXPECT_EQ(node, k0);
  }
  // The points only k1 and one other keyframe saw are gone with it (2 observations -> 1 -> bad).
  EXPECT_GT(t.map.erase_bad_map_points(), 0u);
  // Relative pose kept for trajectory output.
  const auto rel = k1->cam_from_parent_at_erase();
  EXPECT_LT((rel.matrix() - (k1->cam_from_world() * k0->world_from_cam()).matrix()).norm(), 1e-12);
}

TEST(KeyFrame, FirstKeyframeIsNeverErasedAndProtectionDefersErase) {
  TestMap t;
  auto k0 = t.add_keyframe(), k1 = t.add_keyframe();
  k0->set_bad(t.map);
  EXPECT_FALSE(k0->is_bad());
  k1->set_not_erase();
  k1->set_bad(t.map);
  EXPECT_FALSE(k1->is_bad());
  k1->set_erase(t.map);
  EXPECT_TRUE(k1->is_bad());
}

TEST(Map, ClearFreesEverything) {
  std::weak_ptr<KeyFrame> weak_kf;
  std::weak_ptr<MapPoint> weak_point;
  {
    TestMap t;
    auto a = t.add_keyframe(), b = t.add_keyframe();
    for (size_t i = 0; i < 20; ++i) t.add_point({a, b}, i);
    b->update_connections();
    weak_kf = b;
    weak_point = t.map.map_points().front();
    a.reset();
    b.reset();
    t.map.clear();
    EXPECT_EQ(t.map.num_keyframes(), 0u);
  }
  EXPECT_TRUE(weak_kf.expired());
  EXPECT_TRUE(weak_point.expired());
}
