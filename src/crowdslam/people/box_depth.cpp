#include "crowdslam/people/box_depth.h"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <vector>

#include "crowdslam/people/detector.h"

namespace crowdslam::people {

namespace {

constexpr double kMinStripPx = 64.0;  // inner strips of a box at the image's edge (box_depth_test)

struct Patch {
  double u = 0;
  double v = 0;
  double depth_m = -1.0;  // median, <= 0 when fewer than 10 valid pixels
};

// Median depth of the region [x0, x1) x [y0, y1) in box-relative units (0..1 span the box, outside is
// allowed), clipped to the image; subsampled to about 400 pixels.
Patch patch(const cv::Mat& depth, double factor, const cv::Rect2f& box, double x0, double y0, double x1,
            double y1) {
  const cv::Rect region =
      cv::Rect(cv::Point(cvFloor(box.x + x0 * box.width), cvFloor(box.y + y0 * box.height)),
               cv::Point(cvCeil(box.x + x1 * box.width), cvCeil(box.y + y1 * box.height))) &
      cv::Rect(0, 0, depth.cols, depth.rows);
  Patch p;
  if (region.area() <= 0) return p;
  p.u = region.x + 0.5 * region.width;
  p.v = region.y + 0.5 * region.height;
  // The patch sits where its depths were measured: with holes in part of the region (stereo near the
  // image's edge) the median depth belongs to the measured part, not to the region's centre.
  double sum_u = 0;
  double sum_v = 0;
  std::vector<uint16_t> values = sample_valid_depths(depth, region, 400, &sum_u, &sum_v);
  if (values.size() < 10) return p;
  p.u = sum_u / static_cast<double>(values.size());
  p.v = sum_v / static_cast<double>(values.size());
  const auto mid = values.begin() + static_cast<long>(values.size() / 2);
  std::nth_element(values.begin(), mid, values.end());
  p.depth_m = *mid / factor;
  return p;
}

// Along rows through the torso (25-55 % of the box's height), from the box's middle towards one side and
// a quarter of its width past it: a step in depth between neighbouring measured pixels (at most 4 px
// apart) from the torso's surface (not behind the torso by more than `margin_m`) to at least `margin_m`
// and 10 % farther, the far side holding for the next 4 measurements. A surface that continues (a wall, a
// poster on it, frontal or oblique) changes depth smoothly; a body ends at its outline with the background
// behind it. The median depth behind the edge when at least two of the four rows show one.
std::optional<double> occluding_edge(const cv::Mat& depth, double factor, const cv::Rect2f& box, double torso_m,
                                     double margin_m, bool towards_right) {
  constexpr int kMaxGapPx = 4;
  constexpr int kHold = 4;
  const int from = std::clamp(cvRound(box.x + 0.5 * box.width), 0, depth.cols - 1);
  const int to = std::clamp(cvRound(towards_right ? box.x + 1.25 * box.width : box.x - 0.25 * box.width), 0,
                            depth.cols - 1);
  const int step = towards_right ? 1 : -1;
  std::vector<double> behind;
  int rows_with_edge = 0;
  for (const double at : {0.25, 0.35, 0.45, 0.55}) {
    const int v = cvRound(box.y + at * box.height);
    if (v < 0 || v >= depth.rows) continue;
    const auto* row = depth.ptr<uint16_t>(v);
    double last = -1.0;
    int last_u = from;
    for (int u = from; u != to + step; u += step) {
      if (row[u] == 0) continue;
      const double z = row[u] / factor;
      if (last > 0 && std::abs(u - last_u) <= kMaxGapPx && last <= torso_m + margin_m &&
          z - last > std::max(margin_m, 0.1 * last)) {
        // The far side must hold: the next kHold measurements stay behind the near side.
        int held = 0;
        for (int w = u + step; w != to + step && held < kHold; w += step) {
          if (row[w] == 0) continue;
          if (row[w] / factor - last <= margin_m) break;
          ++held;
        }
        if (held == kHold) {
          ++rows_with_edge;
          behind.push_back(z);
          break;
        }
      }
      last = z;
      last_u = u;
    }
  }
  if (rows_with_edge < 2) return std::nullopt;
  std::nth_element(behind.begin(), behind.begin() + static_cast<long>(behind.size() / 2), behind.end());
  return behind[behind.size() / 2];
}

}  // namespace

std::vector<uint16_t> sample_valid_depths(const cv::Mat& depth_image_raw, const cv::Rect& region_in,
                                          int max_samples, double* sum_u, double* sum_v) {
  const cv::Rect region = region_in & cv::Rect(0, 0, depth_image_raw.cols, depth_image_raw.rows);
  std::vector<uint16_t> values;
  if (region.area() <= 0 || max_samples < 1) return values;
  const int step = std::max(1, static_cast<int>(std::sqrt(region.area() / static_cast<double>(max_samples))));
  for (int y = region.y; y < region.y + region.height; y += step) {
    const auto* row = depth_image_raw.ptr<uint16_t>(y);
    for (int x = region.x; x < region.x + region.width; x += step) {
      if (row[x] <= 0) continue;
      values.push_back(row[x]);
      if (sum_u) *sum_u += x;
      if (sum_v) *sum_v += y;
    }
  }
  return values;
}

BoxDepthTest box_depth_test(const cv::Mat& depth_image_raw, double depth_factor, const cv::Rect2f& box,
                            double margin_m, const std::vector<cv::Rect2f>& other_people) {
  BoxDepthTest test;
  if (depth_image_raw.empty() || depth_image_raw.type() != CV_16UC1 || !(depth_factor > 0)) return test;
  if (!(box.width > 1) || !(box.height > 1)) return test;
  std::vector<cv::Rect2f> others;
  for (const auto& o : other_people) {
    const float overlap = (o & box).area();
    if (overlap < 0.5F * (o.area() + box.area() - overlap)) others.push_back(o);
  }
  // A patch that shows another person says nothing about the surface behind this one.
  auto on_other_person = [&](const Patch& p) {
    return std::any_of(others.begin(), others.end(), [&](const cv::Rect2f& o) {
      return p.u >= o.x && p.u < o.x + o.width && p.v >= o.y && p.v < o.y + o.height;
    });
  };
  const Patch torso = patch(depth_image_raw, depth_factor, box, 0.35, 0.2, 0.65, 0.55);
  if (torso.depth_m <= 0) return test;
  test.torso_m = torso.depth_m;
  // Outside patches, by side: left, right, above.
  const Patch sides[3][3] = {
      {patch(depth_image_raw, depth_factor, box, -0.25, 0.0, 0.0, 0.33),
       patch(depth_image_raw, depth_factor, box, -0.25, 0.33, 0.0, 0.67),
       patch(depth_image_raw, depth_factor, box, -0.25, 0.67, 0.0, 1.0)},
      {patch(depth_image_raw, depth_factor, box, 1.0, 0.0, 1.25, 0.33),
       patch(depth_image_raw, depth_factor, box, 1.0, 0.33, 1.25, 0.67),
       patch(depth_image_raw, depth_factor, box, 1.0, 0.67, 1.25, 1.0)},
      {patch(depth_image_raw, depth_factor, box, 0.0, -0.125, 0.5, 0.0),
       patch(depth_image_raw, depth_factor, box, 0.5, -0.125, 1.0, 0.0), Patch{}},
  };
  // Planes through the patches of every pair of sides (and all three): a box is flat only when each of
  // them says so. A wall continuing past the box agrees on every side; a person beside a crate or another
  // person (one side as close as they are) still stands out against the other sides.
  const double scale = 1.0 / std::max(depth_image_raw.cols, depth_image_raw.rows);
  auto gap_from = [&](const std::vector<const Patch*>& around) -> std::optional<double> {
    if (around.size() < 3) return std::nullopt;
    // 1/z = a u + b v + c, least squares over the patches (pixels scaled to ~1 for conditioning).
    Eigen::MatrixXd a(static_cast<Eigen::Index>(around.size()), 3);
    Eigen::VectorXd b(static_cast<Eigen::Index>(around.size()));
    for (size_t i = 0; i < around.size(); ++i) {
      a.row(static_cast<Eigen::Index>(i)) << around[i]->u * scale, around[i]->v * scale, 1.0;
      b(static_cast<Eigen::Index>(i)) = 1.0 / around[i]->depth_m;
    }
    const Eigen::Vector3d plane = a.colPivHouseholderQr().solve(b);
    const double inverse = plane.dot(Eigen::Vector3d(torso.u * scale, torso.v * scale, 1.0));
    // A plane that does not reach the torso's ray in front of the camera: the surroundings are not one
    // surface there, nothing to compare with.
    if (!(inverse > 1e-6)) return std::nullopt;
    return 1.0 / inverse;
  };
  // The patches by side: all of them, and those that do not show another person beside this one.
  std::vector<const Patch*> all[3];
  std::vector<const Patch*> clear[3];
  bool beside_people = false;  // some patch outside the box shows another person at this one's depth
  for (int s = 0; s < 3; ++s) {
    for (const Patch& p : sides[s]) {
      if (p.depth_m <= 0) continue;
      all[s].push_back(&p);
      // Another person behind this one still shows that this one stands out; one beside them at their
      // depth (or in front) says nothing about the surface behind them.
      if (on_other_person(p) && p.depth_m <= torso.depth_m + margin_m) {
        beside_people = true;
      } else {
        clear[s].push_back(&p);
      }
    }
  }
  // The surface the torso stands out of most, over the planes through pairs of sides and all three.
  auto deepest_surface = [&](const std::vector<const Patch*> (&by_side)[3]) -> std::optional<double> {
    const int combinations[4][3] = {{0, 1, 2}, {0, 1, -1}, {0, 2, -1}, {1, 2, -1}};
    std::optional<double> deepest;
    for (const auto& combination : combinations) {
      std::vector<const Patch*> around;
      int sides_used = 0;
      for (const int s : combination) {
        if (s < 0 || by_side[s].empty()) continue;
        around.insert(around.end(), by_side[s].begin(), by_side[s].end());
        ++sides_used;
      }
      if (sides_used < 2) continue;
      const auto surface = gap_from(around);
      if (surface && (!deepest || *surface > *deepest)) deepest = *surface;
    }
    return deepest;
  };
  std::optional<double> surface = deepest_surface(all);
  // Flat on every side, people beside it included: flat only if the sides that do not show people say so
  // too (undecided without them).
  if (surface && *surface - test.torso_m <= margin_m && beside_people) {
    surface = deepest_surface(clear);
    if (!surface) return test;
  }
  bool decided = surface.has_value();
  if (surface) test.surface_m = *surface;
  // Near the edge: too little room outside the box for a patch with keypoints in it.
  const auto near = static_cast<float>(kMinStripPx);
  const bool at_left_edge = box.x < near;
  const bool at_right_edge = box.x + box.width > static_cast<float>(depth_image_raw.cols) - near;
  const bool at_side_edge = at_left_edge || at_right_edge;
  // (Not beside other people: the strips inside a box among people show people too.)
  if (!decided && at_side_edge && !beside_people) {
    // The box reaches the image's left or right edge and fewer than two sides outside it have depth (a
    // false positive filling the image's width): strips just inside its left and right edges
    // stand in for them. Beside a standing person those strips are mostly background (the box spans the
    // arms and legs, the torso sits in the middle); on a wall they are wall. Holes in the depth image
    // around a box inside the image still leave it undecided.
    // Each strip 15 % of the box's width. A strip without depth is widened to kMinStripPx (a third of
    // the box at most): in stereo there are no ORB keypoints within ~20 px of the image's edge and no
    // right-image match closer to the left edge than the disparity, so a narrow strip there holds no
    // depth even on a wall. (Wider strips everywhere judged people who fill a narrow box at the edge,
    // entering the view, on themselves: flat.)
    const double wide = std::min(1.0 / 3.0, std::max(0.15, kMinStripPx / box.width));
    auto strip = [&](bool left, double w) {
      std::array<Patch, 3> p;
      const double x0 = left ? 0.0 : 1.0 - w;
      const double y[4] = {0.0, 0.33, 0.67, 1.0};
      for (int k = 0; k < 3; ++k)
        p[static_cast<size_t>(k)] = patch(depth_image_raw, depth_factor, box, x0, y[k], x0 + w, y[k + 1]);
      return p;
    };
    auto has_depth = [](const std::array<Patch, 3>& p) {
      return std::any_of(p.begin(), p.end(), [](const Patch& q) { return q.depth_m > 0; });
    };
    std::array<Patch, 3> inner[2] = {strip(true, 0.15), strip(false, 0.15)};
    for (int side = 0; side < 2; ++side) {
      if (!has_depth(inner[side]) && wide > 0.15) inner[side] = strip(side == 0, wide);
    }
    std::vector<const Patch*> around;
    int sides_used = 0;
    for (const auto& strip : inner) {
      int before = static_cast<int>(around.size());
      for (const Patch& p : strip) {
        if (p.depth_m > 0) around.push_back(&p);
      }
      if (static_cast<int>(around.size()) > before) ++sides_used;
    }
    if (sides_used == 2) {
      if (const auto surface = gap_from(around)) {
        test.surface_m = *surface;
        decided = true;
      }
    }
  }
  // At one side edge only (a person close to the camera, cut by the image's edge, fills their box, so the
  // strips inside both its edges may show only them): an occluding edge beside the torso, towards the side
  // the box has outside it, shows a body in front of what is behind it.
  if (at_left_edge != at_right_edge && !beside_people &&
      (!decided || test.surface_m - test.torso_m <= margin_m)) {
    if (const auto behind = occluding_edge(depth_image_raw, depth_factor, box, test.torso_m, margin_m,
                                           /*towards_right=*/at_left_edge)) {
      test.surface_m = *behind;
      decided = true;
    }
  }
  if (!decided) return test;
  test.verdict =
      test.surface_m - test.torso_m > margin_m ? BoxDepthVerdict::kStandsOut : BoxDepthVerdict::kFlat;
  return test;
}

bool flat_by_leader(const cv::Rect2f& box, BoxDepthVerdict own, const std::vector<PersonBox>& nms_boxes,
                    const std::vector<BoxDepthVerdict>& nms_verdicts) {
  if (own == BoxDepthVerdict::kFlat) return true;
  const int leader = most_overlapping(box, nms_boxes);
  return leader >= 0 && static_cast<size_t>(leader) < nms_verdicts.size() &&
         nms_verdicts[static_cast<size_t>(leader)] == BoxDepthVerdict::kFlat;
}

}  // namespace crowdslam::people
