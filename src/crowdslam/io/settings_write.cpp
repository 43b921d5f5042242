// write_settings: YAML that cv::FileStorage (and ORB-SLAM2) reads back to the same values.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>

#include "crowdslam/io/settings.h"
#include "crowdslam/util/atomic_file.h"

namespace crowdslam::io {
namespace {

// Shortest of %.15g / %.17g that reads back exactly; always looks like a real (has '.', 'e' or "inf").
std::string real_text(double value) {
  char buffer[40];
  std::snprintf(buffer, sizeof(buffer), "%.15g", value);
  if (std::strtod(buffer, nullptr) != value) std::snprintf(buffer, sizeof(buffer), "%.17g", value);
  std::string text(buffer);
  if (text.find_first_of(".eEn") == std::string::npos) text += ".0";
  return text;
}

std::string quoted(const std::string& text) {
  std::string out = "\"";
  for (const char ch : text) {
    if (ch == '"' || ch == '\\') out += '\\';
    out += ch;
  }
  return out + "\"";
}

std::string list_text(const std::vector<double>& values) {
  std::string out = "[";
  for (std::size_t i = 0; i < values.size(); ++i) out += (i ? ", " : " ") + real_text(values[i]);
  return out + " ]";
}

void write_matrix(std::ostream& out, const std::string& key, const cv::Mat& matrix) {
  cv::Mat m;
  matrix.convertTo(m, CV_64F);
  out << key << ": !!opencv-matrix\n   rows: " << m.rows << "\n   cols: " << m.cols
      << "\n   dt: d\n   data: [";
  for (int r = 0; r < m.rows; ++r)
    for (int c = 0; c < m.cols; ++c) out << ((r || c) ? ", " : " ") << real_text(m.at<double>(r, c));
  out << " ]\n";
}

void write_side(std::ostream& out, const std::string& side, const geometry::RectificationSide& s) {
  out << side << ".height: " << s.height << "\n" << side << ".width: " << s.width << "\n";
  write_matrix(out, side + ".D", s.D);
  write_matrix(out, side + ".K", s.K);
  write_matrix(out, side + ".R", s.R);
  write_matrix(out, side + ".P", s.P);
}

void write_camera(std::ostream& out, const Settings& s) {
  const auto& c = s.camera;
  out << "# Camera (of the images SLAM works on: rectified for stereo with LEFT/RIGHT blocks)\n";
  out << "Camera.fx: " << real_text(c.fx) << "\nCamera.fy: " << real_text(c.fy)
      << "\nCamera.cx: " << real_text(c.cx) << "\nCamera.cy: " << real_text(c.cy) << "\n\n";
  out << "Camera.k1: " << real_text(c.k1) << "\nCamera.k2: " << real_text(c.k2)
      << "\nCamera.p1: " << real_text(c.p1) << "\nCamera.p2: " << real_text(c.p2)
      << "\nCamera.k3: " << real_text(c.k3) << "\n\n";
  if (c.width > 0) out << "Camera.width: " << c.width << "\n";
  if (c.height > 0) out << "Camera.height: " << c.height << "\n";
  out << "Camera.fps: " << real_text(c.fps) << "\n";
  if (s.has_baseline) out << "Camera.bf: " << real_text(c.bf) << "\n";
  out << "# Colour order of the images (0: BGR, 1: RGB; ignored for grey images)\nCamera.RGB: "
      << (c.rgb ? 1 : 0) << "\n\n";
  out << "# Close/far threshold (baseline multiples)\nThDepth: " << real_text(s.th_depth) << "\n";
  if (s.has_depth_map_factor)
    out << "# Depth map values factor (raw / factor = metres)\nDepthMapFactor: "
        << real_text(s.depth_map_factor) << "\n";
  out << "\n";
}

void write_orb(std::ostream& out, const OrbSettings& o) {
  out << "# ORB extractor\nORBextractor.nFeatures: " << o.n_features
      << "\nORBextractor.scaleFactor: " << real_text(o.scale_factor)
      << "\nORBextractor.nLevels: " << o.n_levels << "\nORBextractor.iniThFAST: " << o.ini_th_fast
      << "\nORBextractor.minThFAST: " << o.min_th_fast << "\n\n";
}

void write_own_sections(std::ostream& out, const Settings& s) {
  const auto& d = s.detector;
  out << "# Person detector (OpenCV DNN; docs/DETECTION.md)\n";
  out << "Detector.model_cfg: " << quoted(d.model_cfg)
      << "\nDetector.model_weights: " << quoted(d.model_weights) << "\nDetector.input_size: " << d.input_size;
  // Written only when set, so files written for a square input read the same in older versions.
  if (d.input_width > 0 || d.input_height > 0)
    out << "\nDetector.input_width: " << d.input_width << "\nDetector.input_height: " << d.input_height;
  if (d.backend != "auto") out << "\nDetector.backend: " << quoted(d.backend);
  if (d.preprocess != "auto") out << "\nDetector.preprocess: " << quoted(d.preprocess);
  if (d.resize != "auto") out << "\nDetector.resize: " << quoted(d.resize);
  out << "\nDetector.confidence: " << real_text(d.confidence) << "\nDetector.nms: " << real_text(d.nms)
      << "\nDetector.person_class: " << d.person_class
      << (d.filter_before_nms ? std::string("\nDetector.filter_before_nms: ") + (*d.filter_before_nms ? "1" : "0")
                              : std::string())
      << "\nDetector.raw_box_max_area_ratio: " << real_text(d.raw_box_max_area_ratio)
      << "\nDetector.mode: " << quoted(d.mode) << "\nDetector.latest_interval: " << d.latest_interval
      << "\nDetector.tracker: " << (d.tracker ? 1 : 0) << "\nDetector.track_iou: " << real_text(d.track_iou)
      << "\nDetector.track_min_hits: " << d.track_min_hits
      << "\nDetector.track_max_misses: " << d.track_max_misses
      << "\nDetector.track_confirm_confidence: " << real_text(d.track_confirm_confidence) << "\n\n";
  const auto& p = s.people_filter;
  out << "# Keypoints on people (mode \"paper\" or \"depth\")\nPeopleFilter.enabled: " << (p.enabled ? 1 : 0)
      << "\nPeopleFilter.mode: " << quoted(p.mode) << "\nPeopleFilter.margin_px: " << real_text(p.margin_px)
      << "\nPeopleFilter.depth_margin_m: " << real_text(p.depth_margin_m)
      << "\nPeopleFilter.silhouettes: " << (p.silhouettes ? 1 : 0)
      << "\nPeopleFilter.segment_from_m: " << real_text(p.segment_from_m)
      << "\nPeopleFilter.right_image: " << quoted(p.right_image)
      << "\nPeopleFilter.static_in_boxes: " << quoted(p.static_in_boxes)
      << "\nPeopleFilter.static_check_below: " << p.static_check_below
      << "\nPeopleFilter.flat_box_margin_m: " << real_text(p.flat_box_margin_m) << "\n\n";
  const auto& g = s.geometry;
  out << "# Geometric dynamic check of tracked keypoints\nGeometry.dynamic_check: "
      << (g.dynamic_check ? 1 : 0) << "\nGeometry.moving_factor: " << real_text(g.moving_factor)
      << "\nGeometry.certain_factor: " << real_text(g.certain_factor)
      << "\nGeometry.dynamic_score: " << g.dynamic_score << "\nGeometry.cull_score: " << g.cull_score
      << "\nGeometry.region_radius_px: " << real_text(g.region_radius_px)
      << "\nGeometry.region_depth_m: " << real_text(g.region_depth_m)
      << "\nGeometry.region_depth_ratio: " << real_text(g.region_depth_ratio)
      << "\nGeometry.region_steps: " << g.region_steps
      << "\nGeometry.free_space_margin_m: " << real_text(g.free_space_margin_m)
      << "\nGeometry.free_space_ratio: " << real_text(g.free_space_ratio)
      << "\nGeometry.free_space_cull_run: " << g.free_space_cull_run << "\n\n";
  out << "# Tracking through views the map does not cover (RGB-D / stereo), and through people hiding it\n"
      << "Tracking.odometry_bridge_min_inliers: " << s.tracking.odometry_bridge_min_inliers
      << "\nTracking.bridge_max_s: " << real_text(s.tracking.bridge_max_s)
      << "\nTracking.bridge_min_people_share: " << real_text(s.tracking.bridge_min_people_share)
      << "\nTracking.reanchor_max_s: " << real_text(s.tracking.reanchor_max_s)
      << "\nTracking.odometry_sigma_deg: " << real_text(s.tracking.odometry_sigma_deg)
      << "\nTracking.keyframe_reference_ratio: " << real_text(s.tracking.keyframe_reference_ratio) << "\n\n";
  out << "# A monocular camera at a constant height above the ground (a car's)\nGround.enabled: "
      << (s.ground.enabled ? 1 : 0) << "\nGround.keyframe_sigma: " << real_text(s.ground.keyframe_sigma) << "\n\n";
  const auto& b = s.feature_budget;
  out << "# Feature budget: factor on nFeatures by fraction of the image covered by "
         "people\nFeatureBudget.enabled: "
      << (b.enabled ? 1 : 0) << "\nFeatureBudget.thresholds: " << list_text(b.thresholds)
      << "\nFeatureBudget.factors: " << list_text(b.factors) << "\nFeatureBudget.area: " << quoted(b.area)
      << "\n\n";
  out << "# Output\nOutput.trajectory_format: " << quoted(s.output.trajectory_format) << "\n";
}

}  // namespace

void write_settings(const std::string& path, const Settings& settings) {
  std::ostringstream out;
  out << "%YAML:1.0\n---\n# crowdslam settings (ORB-SLAM2 compatible keys plus our own sections)\n\n";
  write_camera(out, settings);
  write_orb(out, settings.orb);
  if (settings.rectification) {
    out << "# Stereo rectification\n";
    write_side(out, "LEFT", settings.rectification->left);
    write_side(out, "RIGHT", settings.rectification->right);
    out << "\n";
  }
  write_own_sections(out, settings);
  write_file_atomic(path, out.str());
}

}  // namespace crowdslam::io
