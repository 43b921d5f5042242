// Keyframe database on hand-made bags of words: which keyframes are candidates follows in closed form
// from the shared words, the L1 scores and the covisibility groups.
#include <gtest/gtest.h>

#include <atomic>
#include <thread>

#include "crowdslam/loop/keyframe_database.h"
#include "crowdslam/map/map.h"

using namespace crowdslam;
using map::KeyFrame;

namespace {

// word -> weight (normalised to sum 1 here, as Vocabulary::transform does).
std::shared_ptr<map::FrameFeatures> features_of(const std::vector<std::pair<bow::WordId, double>>& words) {
  auto f = std::make_shared<map::FrameFeatures>();
  for (const auto& [word, weight] : words) f->bow[word] = weight;
  bow::normalize_l1(f->bow);
  return f;
}

// Words first..last, equal weights.
std::vector<std::pair<bow::WordId, double>> range(bow::WordId first, bow::WordId last, double weight = 1.0) {
  std::vector<std::pair<bow::WordId, double>> words;
  for (bow::WordId w = first; w <= last; ++w) words.emplace_back(w, weight);
  return words;
}

std::vector<std::pair<bow::WordId, double>> concat(std::vector<std::pair<bow::WordId, double>> a,
                                                   const std::vector<std::pair<bow::WordId, double>>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

struct Fixture {
  std::shared_ptr<geometry::PinholeCamera> camera = std::make_shared<geometry::PinholeCamera>();
  std::shared_ptr<map::ScaleLevels> levels = std::make_shared<map::ScaleLevels>(1.2f, 8);
  map::Map map;
  loop::KeyframeDatabase database;

  std::shared_ptr<KeyFrame> keyframe(const std::vector<std::pair<bow::WordId, double>>& words, bool add = true) {
    auto kf = std::make_shared<KeyFrame>(map.next_keyframe_id(), 0, 0.0, camera, levels, features_of(words),
                                         geometry::SE3::identity());
    map.add_keyframe(kf);
    if (add) database.add(kf);
    return kf;
  }
};

void connect(const std::shared_ptr<KeyFrame>& a, const std::shared_ptr<KeyFrame>& b, int weight = 30) {
  a->add_connection(b, weight);
  b->add_connection(a, weight);
}

std::vector<uint64_t> ids(const std::vector<std::shared_ptr<KeyFrame>>& keyframes) {
  std::vector<uint64_t> out;
  for (const auto& kf : keyframes) out.push_back(kf->id);
  return out;
}

// Query: words 1..10, 0.1 each.
//   a: the same words               -> 10 common, score 1.0
//   b: words 1..9 and 50            ->  9 common, score 0.9
//   c: words 1..5 and 51..55        ->  5 common (< 0.8 x 10): never scored
//   d: words 1..8 and 60, 61 with most weight on 60, 61 -> 8 common, score 8 x 0.025 = 0.2
//   e: words 200..210               ->  no word in common
struct Scene : Fixture {
  std::shared_ptr<KeyFrame> zero = keyframe(range(1000, 1005));  // id 0 (never erased by set_bad)
  std::shared_ptr<KeyFrame> a = keyframe(range(1, 10));
  std::shared_ptr<KeyFrame> b = keyframe(concat(range(1, 9), range(50, 50)));
  std::shared_ptr<KeyFrame> c = keyframe(concat(range(1, 5), range(51, 55)));
  std::shared_ptr<KeyFrame> d = keyframe(concat(range(1, 8, 0.025), range(60, 61, 0.4)));
  std::shared_ptr<KeyFrame> e = keyframe(range(200, 210));
  std::shared_ptr<map::FrameFeatures> query = features_of(range(1, 10));
};

TEST(KeyframeDatabase, ScoresAsExpected) {
  Scene s;
  EXPECT_NEAR(bow::l1_score(s.query->bow, s.a->features->bow), 1.0, 1e-12);
  EXPECT_NEAR(bow::l1_score(s.query->bow, s.b->features->bow), 0.9, 1e-12);
  EXPECT_NEAR(bow::l1_score(s.query->bow, s.d->features->bow), 0.2, 1e-12);
  EXPECT_EQ(s.database.size(), 6u);
}

TEST(KeyframeDatabase, RelocalizationCandidatesShareEnoughWordsAndScoreWell) {
  Scene s;
  // No covisibility: every keyframe is its own group. a (1.0) and b (0.9 >= 0.75) qualify; d scores 0.2;
  // c shares too few words; e none.
  EXPECT_EQ(ids(s.database.relocalization_candidates(*s.query)), (std::vector<uint64_t>{s.a->id, s.b->id}));
}

TEST(KeyframeDatabase, CovisibleKeyframesFormOneGroupReturnedOnce) {
  Scene s;
  // a and b covisible: both groups score 1.9 and both name a as their best: a is returned once.
  connect(s.a, s.b);
  EXPECT_EQ(ids(s.database.relocalization_candidates(*s.query)), (std::vector<uint64_t>{s.a->id}));
  // d's group with a: 0.2 + 1.0 = 1.2 < 0.75 x (1.0 + 0.9 + 0.2) = 1.575: still only a.
  connect(s.d, s.a);
  EXPECT_EQ(ids(s.database.relocalization_candidates(*s.query)), (std::vector<uint64_t>{s.a->id}));
}

TEST(KeyframeDatabase, GroupsAccumulateOnlyNeighboursThatWereScored) {
  Scene s;
  // c shares 5 words (not scored): connecting it to b must not lift b's group.
  connect(s.c, s.b);
  connect(s.e, s.b);
  EXPECT_EQ(ids(s.database.relocalization_candidates(*s.query)), (std::vector<uint64_t>{s.a->id, s.b->id}));
}

TEST(KeyframeDatabase, EmptyQueryAndNoSharedWordsGiveNothing) {
  Scene s;
  map::FrameFeatures empty;
  EXPECT_TRUE(s.database.relocalization_candidates(empty).empty());
  EXPECT_TRUE(s.database.relocalization_candidates(*features_of(range(5000, 5010))).empty());
}

TEST(KeyframeDatabase, BadAndExpiredKeyframesAreSkippedAndDropped) {
  Scene s;
  s.a->set_bad(s.map);
  ASSERT_TRUE(s.a->is_bad());
  // Without a, the most common words is 9 (b): d (8 >= 7.2) is scored now, but 0.2 < 0.75 x 0.9.
  EXPECT_EQ(ids(s.database.relocalization_candidates(*s.query)), (std::vector<uint64_t>{s.b->id}));
  EXPECT_EQ(s.database.size(), 5u);  // a dropped by the query

  const uint64_t b_id = s.b->id;
  s.map.erase_keyframe(b_id);
  s.b.reset();  // the last owner: the database holds it weakly
  // Now d has the most common words (8): it is the only one scored, and so the best.
  EXPECT_EQ(ids(s.database.relocalization_candidates(*s.query)), (std::vector<uint64_t>{s.d->id}));
  EXPECT_EQ(s.database.size(), 4u);
}

TEST(KeyframeDatabase, EraseAndClear) {
  Scene s;
  s.database.erase(s.a->id);
  EXPECT_EQ(s.database.size(), 5u);
  EXPECT_EQ(ids(s.database.relocalization_candidates(*s.query)), (std::vector<uint64_t>{s.b->id}));
  s.database.erase(s.a->id);  // not indexed any more: no-op
  s.database.add(s.b);        // already indexed: no-op
  EXPECT_EQ(s.database.size(), 5u);
  EXPECT_EQ(ids(s.database.relocalization_candidates(*s.query)), (std::vector<uint64_t>{s.b->id}));
  s.database.clear();
  EXPECT_EQ(s.database.size(), 0u);
  EXPECT_TRUE(s.database.relocalization_candidates(*s.query).empty());
  s.database.add(s.a);
  EXPECT_EQ(ids(s.database.relocalization_candidates(*s.query)), (std::vector<uint64_t>{s.a->id}));
}

TEST(KeyframeDatabase, LoopCandidatesExcludeTheKeyframeAndItsConnectedKeyframes) {
  Scene s;
  // The query is keyframe q (words 1..10, in the database); a is covisible with q.
  auto q = s.keyframe(range(1, 10));
  connect(q, s.a);
  // Candidates without q and a: b has the most common words (9); d (8 >= 7.2) scores 0.2.
  EXPECT_EQ(ids(s.database.loop_candidates(*q, 0.0)), (std::vector<uint64_t>{s.b->id}));
  EXPECT_EQ(ids(s.database.loop_candidates(*q, 0.85)), (std::vector<uint64_t>{s.b->id}));
  EXPECT_TRUE(s.database.loop_candidates(*q, 0.95).empty());
  // Below min_score d does not start a group, but as b's covisible neighbour it still counts in b's.
  connect(s.d, s.b);
  EXPECT_EQ(ids(s.database.loop_candidates(*q, 0.5)), (std::vector<uint64_t>{s.b->id}));
  // Without the exclusion a (score 1.0) would win: check it does for a keyframe not connected to a.
  auto lonely = s.keyframe(range(1, 10));
  const auto candidates = s.database.loop_candidates(*lonely, 0.0);
  ASSERT_FALSE(candidates.empty());
  EXPECT_TRUE(candidates.front()->id == s.a->id || candidates.front()->id == q->id);
  for (const auto& kf : candidates) EXPECT_NE(kf->id, lonely->id);
}

TEST(KeyframeDatabase, ConcurrentAddsAndQueriesKeepEveryKeyframe) {
  Fixture f;
  constexpr int kPerThread = 150;
  // Keyframe k of thread t has words (t * 1000 + k) * 4 .. + 3: unique words, so each query finds its own.
  std::vector<std::vector<std::shared_ptr<KeyFrame>>> made(2);
  for (int t = 0; t < 2; ++t) {
    for (int k = 0; k < kPerThread; ++k) {
      const auto first = static_cast<bow::WordId>((t * 1000 + k) * 4);
      made[t].push_back(f.keyframe(range(first, first + 3), false));
    }
  }
  std::atomic<bool> done{false};
  std::atomic<int> wrong{0};
  std::thread query([&] {
    while (!done) {
      for (int k = 0; k < kPerThread; k += 7) {
        const auto result = f.database.relocalization_candidates(*made[0][static_cast<size_t>(k)]->features);
        // Either not added yet, or exactly itself.
        if (!result.empty() && (result.size() != 1 || result.front() != made[0][static_cast<size_t>(k)])) ++wrong;
      }
    }
  });
  std::vector<std::thread> adders;
  for (int t = 0; t < 2; ++t) {
    adders.emplace_back([&, t] {
      for (const auto& kf : made[t]) f.database.add(kf);
    });
  }
  for (auto& th : adders) th.join();
  done = true;
  query.join();
  EXPECT_EQ(wrong.load(), 0);
  EXPECT_EQ(f.database.size(), 2u * kPerThread);
  for (int t = 0; t < 2; ++t) {
    for (const auto& kf : made[t]) {
      const auto result = f.database.relocalization_candidates(*kf->features);
      ASSERT_EQ(result.size(), 1u);
      EXPECT_EQ(result.front(), kf);
    }
  }
}

}  // namespace
