// Settings::check: every value validated, errors name the file and the key.
#include <cmath>
#include <initializer_list>
#include <sstream>
#include <string>
#include <utility>

#include "crowdslam/io/input_text.h"
#include "crowdslam/io/settings.h"
#include "crowdslam/util/error.h"

namespace crowdslam::io {
namespace {

constexpr double kConsistencyTolerance = 1e-3;  // relative, Camera.* vs LEFT.P / RIGHT.P
// Bounds of what the components accept (feature::ORBExtractor, the feature budget, the detector's
// network input, the tracker's keyframe interval), so a value is reported here with file and key.
constexpr int kMaxImageSide = 65535;
constexpr int kMaxFeatures = 100000;
constexpr int kMaxFastThreshold = 254;
constexpr double kMaxScaleFactor = 4.0;
constexpr double kMaxFps = 10000.0;
constexpr int kMaxDetectorInput = 2048;
constexpr double kMaxBudgetFactor = 10.0;

class Checker {
 public:
  explicit Checker(const std::string& path)
      : path_(path.empty() ? std::string("settings") : clip_text(path)) {}

  [[noreturn]] void fail(const std::string& key, const std::string& reason) const {
    throw input_error(path_, key + ": " + reason);
  }
  template <typename T>
  void require(bool ok, const std::string& key, const std::string& rule, T value) const {
    if (ok) return;
    std::ostringstream os;
    os.precision(17);
    os << "must be " << rule << ", got " << value;
    fail(key, os.str());
  }
  void finite(double value, const std::string& key) const {
    require(std::isfinite(value), key, "finite", value);
  }
  void positive(double value, const std::string& key) const {
    require(std::isfinite(value) && value > 0, key, "> 0", value);
  }
  void close(double value, double expected, const std::string& key, const std::string& other) const {
    const double scale = std::max(std::abs(expected), 1.0);
    if (std::abs(value - expected) <= kConsistencyTolerance * scale) return;
    std::ostringstream os;
    os.precision(17);
    os << "is " << value << " but " << other << " gives " << expected
       << " (Camera.* describe the rectified images)";
    fail(key, os.str());
  }

 private:
  std::string path_;
};

void check_camera(const Checker& c, const CameraSettings& cam, SensorKind sensor) {
  c.positive(cam.fx, "Camera.fx");
  c.positive(cam.fy, "Camera.fy");
  for (const auto& [value, key] : {std::pair{cam.k1, "Camera.k1"},
                                   {cam.k2, "Camera.k2"},
                                   {cam.p1, "Camera.p1"},
                                   {cam.p2, "Camera.p2"},
                                   {cam.k3, "Camera.k3"}})
    c.finite(value, key);
  c.require(cam.width >= 0, "Camera.width", ">= 0", cam.width);
  c.require(cam.height >= 0, "Camera.height", ">= 0", cam.height);
  c.require(cam.width <= kMaxImageSide, "Camera.width", "<= 65535", cam.width);
  c.require(cam.height <= kMaxImageSide, "Camera.height", "<= 65535", cam.height);
  const std::string cx_rule =
      cam.width > 0 ? "in (0, Camera.width=" + std::to_string(cam.width) + ")" : "> 0";
  const std::string cy_rule =
      cam.height > 0 ? "in (0, Camera.height=" + std::to_string(cam.height) + ")" : "> 0";
  c.require(std::isfinite(cam.cx) && cam.cx > 0 && (cam.width == 0 || cam.cx < cam.width), "Camera.cx",
            cx_rule, cam.cx);
  c.require(std::isfinite(cam.cy) && cam.cy > 0 && (cam.height == 0 || cam.cy < cam.height), "Camera.cy",
            cy_rule, cam.cy);
  c.positive(cam.fps, "Camera.fps");
  c.require(cam.fps <= kMaxFps, "Camera.fps", "<= 10000", cam.fps);
  if (sensor != SensorKind::kMonocular) {
    c.positive(cam.bf, "Camera.bf");
  } else {
    c.require(std::isfinite(cam.bf) && cam.bf >= 0, "Camera.bf", ">= 0", cam.bf);
  }
}

void check_orb(const Checker& c, const OrbSettings& o) {
  c.require(o.n_features > 0, "ORBextractor.nFeatures", "> 0", o.n_features);
  c.require(o.n_features <= kMaxFeatures, "ORBextractor.nFeatures", "<= 100000", o.n_features);
  // As a float (the extractor's type) too: 1.00000001 would become 1.
  c.require(std::isfinite(o.scale_factor) && o.scale_factor > 1.0 && static_cast<float>(o.scale_factor) > 1.f,
            "ORBextractor.scaleFactor", "> 1", o.scale_factor);
  c.require(o.scale_factor <= kMaxScaleFactor, "ORBextractor.scaleFactor", "<= 4", o.scale_factor);
  c.require(o.n_levels >= 1 && o.n_levels <= 20, "ORBextractor.nLevels", "in 1..20", o.n_levels);
  c.require(o.min_th_fast > 0, "ORBextractor.minThFAST", "> 0", o.min_th_fast);
  c.require(o.ini_th_fast >= o.min_th_fast, "ORBextractor.iniThFAST", ">= ORBextractor.minThFAST",
            o.ini_th_fast);
  c.require(o.ini_th_fast <= kMaxFastThreshold, "ORBextractor.iniThFAST",
            "<= 254 (a FAST threshold on 8-bit intensities)", o.ini_th_fast);
}

void check_side(const Checker& c, const geometry::RectificationSide& s, const std::string& side) {
  c.require(s.width > 0 && s.width <= kMaxImageSide, side + ".width", "in 1..65535", s.width);
  c.require(s.height > 0 && s.height <= kMaxImageSide, side + ".height", "in 1..65535", s.height);
  auto shape = [&](const cv::Mat& m, int rows, int cols, const std::string& key) {
    if (m.rows != rows || m.cols != cols)
      c.fail(key, "must be " + std::to_string(rows) + "x" + std::to_string(cols) + ", got " +
                      std::to_string(m.rows) + "x" + std::to_string(m.cols));
  };
  shape(s.K, 3, 3, side + ".K");
  shape(s.R, 3, 3, side + ".R");
  shape(s.P, 3, 4, side + ".P");
  const int n = static_cast<int>(s.D.total());
  if ((s.D.rows != 1 && s.D.cols != 1) || (n != 4 && n != 5 && n != 8 && n != 12 && n != 14))
    c.fail(side + ".D", "must be a 1xN vector with N in {4, 5, 8, 12, 14}");
  c.require(s.K.at<double>(0, 0) > 0 && s.K.at<double>(1, 1) > 0, side + ".K", "with positive focal lengths",
            s.K.at<double>(0, 0));
  const cv::Mat should_be_identity = s.R.t() * s.R - cv::Mat::eye(3, 3, CV_64F);
  if (cv::norm(should_be_identity, cv::NORM_INF) > 1e-4 || cv::determinant(s.R) <= 0)
    c.fail(side + ".R", "must be a rotation matrix");
  c.require(s.P.at<double>(0, 0) > 0 && s.P.at<double>(1, 1) > 0, side + ".P", "with positive focal lengths",
            s.P.at<double>(0, 0));
}

void check_rectification(const Checker& c, const geometry::StereoRectification& r, const CameraSettings& cam) {
  check_side(c, r.left, "LEFT");
  check_side(c, r.right, "RIGHT");
  const cv::Mat& p = r.left.P;
  c.close(cam.fx, p.at<double>(0, 0), "Camera.fx", "LEFT.P(0,0)");
  c.close(cam.fy, p.at<double>(1, 1), "Camera.fy", "LEFT.P(1,1)");
  c.close(cam.cx, p.at<double>(0, 2), "Camera.cx", "LEFT.P(0,2)");
  c.close(cam.cy, p.at<double>(1, 2), "Camera.cy", "LEFT.P(1,2)");
  if (cam.bf > 0) c.close(cam.bf, -r.right.P.at<double>(0, 3), "Camera.bf", "-RIGHT.P(0,3)");
}

bool one_of(const std::string& value, std::initializer_list<const char*> allowed) {
  for (const char* a : allowed)
    if (value == a) return true;
  return false;
}

std::string quoted_value(const std::string& value) { return "\"" + value + "\""; }

void check_detector(const Checker& c, const DetectorSettings& d) {
  c.require(d.input_size > 0 && d.input_size % 32 == 0, "Detector.input_size", "a positive multiple of 32",
            d.input_size);
  c.require(d.input_size <= kMaxDetectorInput, "Detector.input_size", "<= 2048", d.input_size);
  // input_width / input_height: both or neither (0 = the square input_size).
  for (const auto& [key, value] : {std::pair{"Detector.input_width", d.input_width},
                                   std::pair{"Detector.input_height", d.input_height}}) {
    c.require(value == 0 || (value > 0 && value % 32 == 0), key, "0 or a positive multiple of 32", value);
    c.require(value <= kMaxDetectorInput, key, "<= 2048", value);
  }
  if ((d.input_width == 0) != (d.input_height == 0))
    c.fail(d.input_width == 0 ? "Detector.input_width" : "Detector.input_height",
           "must be set together with " +
               std::string(d.input_width == 0 ? "Detector.input_height" : "Detector.input_width") +
               " (or leave both unset and use Detector.input_size)");
  c.require(one_of(d.backend, {"auto", "darknet", "yolo-onnx", "yolox"}), "Detector.backend",
            "\"auto\", \"darknet\", \"yolo-onnx\" or \"yolox\"", quoted_value(d.backend));
  c.require(one_of(d.preprocess, {"auto", "darknet", "yolox", "bytetrack"}), "Detector.preprocess",
            "\"auto\", \"darknet\", \"yolox\" or \"bytetrack\"", quoted_value(d.preprocess));
  c.require(one_of(d.resize, {"auto", "stretch", "letterbox"}), "Detector.resize",
            "\"auto\", \"stretch\" or \"letterbox\"", quoted_value(d.resize));
  c.require(std::isfinite(d.confidence) && d.confidence > 0 && d.confidence <= 1, "Detector.confidence",
            "in (0, 1]", d.confidence);
  c.require(std::isfinite(d.nms) && d.nms > 0 && d.nms <= 1, "Detector.nms", "in (0, 1]", d.nms);
  c.require(d.latest_interval >= 1, "Detector.latest_interval", ">= 1", d.latest_interval);
  c.require(std::isfinite(d.raw_box_max_area_ratio) &&
                (d.raw_box_max_area_ratio == 0 || d.raw_box_max_area_ratio >= 1),
            "Detector.raw_box_max_area_ratio", "0 (off) or >= 1", d.raw_box_max_area_ratio);
  c.require(d.person_class >= 0, "Detector.person_class", ">= 0", d.person_class);
  c.require(d.mode == "every_frame" || d.mode == "latest", "Detector.mode", "\"every_frame\" or \"latest\"",
            "\"" + d.mode + "\"");
  c.require(std::isfinite(d.track_iou) && d.track_iou > 0 && d.track_iou <= 1, "Detector.track_iou",
            "in (0, 1]", d.track_iou);
  c.require(d.track_min_hits >= 1, "Detector.track_min_hits", ">= 1", d.track_min_hits);
  c.require(d.track_max_misses >= 0, "Detector.track_max_misses", ">= 0", d.track_max_misses);
  c.require(std::isfinite(d.track_confirm_confidence) && d.track_confirm_confidence >= 0 &&
                d.track_confirm_confidence <= 1,
            "Detector.track_confirm_confidence", "in [0, 1]", d.track_confirm_confidence);
}

void check_own_sections(const Checker& c, const Settings& s) {
  check_detector(c, s.detector);
  const auto& p = s.people_filter;
  c.require(p.mode == "paper" || p.mode == "depth", "PeopleFilter.mode", "\"paper\" or \"depth\"",
            "\"" + p.mode + "\"");
  c.require(std::isfinite(p.margin_px) && p.margin_px >= 0, "PeopleFilter.margin_px", ">= 0", p.margin_px);
  c.require(p.right_image == "matched" || p.right_image == "boxes", "PeopleFilter.right_image",
            "\"matched\" or \"boxes\"", "\"" + p.right_image + "\"");
  c.require(std::isfinite(p.depth_margin_m) && p.depth_margin_m >= 0, "PeopleFilter.depth_margin_m", ">= 0",
            p.depth_margin_m);
  c.require(std::isfinite(p.segment_from_m) && p.segment_from_m >= 0, "PeopleFilter.segment_from_m", ">= 0",
            p.segment_from_m);
  c.require(p.static_check_below >= 0, "PeopleFilter.static_check_below", ">= 0", p.static_check_below);
  c.require(std::isfinite(p.flat_box_margin_m) && p.flat_box_margin_m >= 0, "PeopleFilter.flat_box_margin_m",
            ">= 0", p.flat_box_margin_m);
  c.require(p.static_in_boxes == "auto" || p.static_in_boxes == "monocular" || p.static_in_boxes == "always" ||
                p.static_in_boxes == "never",
            "PeopleFilter.static_in_boxes", "\"auto\", \"monocular\", \"always\" or \"never\"",
            "\"" + p.static_in_boxes + "\"");
  const auto& g = s.geometry;
  c.require(std::isfinite(g.moving_factor) && g.moving_factor > 0, "Geometry.moving_factor", "> 0",
            g.moving_factor);
  c.require(std::isfinite(g.certain_factor) && (g.certain_factor == 0 || g.certain_factor >= g.moving_factor),
            "Geometry.certain_factor", "0 (off) or >= Geometry.moving_factor", g.certain_factor);
  c.require(g.dynamic_score >= 1, "Geometry.dynamic_score", ">= 1", g.dynamic_score);
  c.require(g.cull_score >= g.dynamic_score && g.cull_score <= 8, "Geometry.cull_score",
            ">= Geometry.dynamic_score and <= 8 (verdicts among a map point's last 8)", g.cull_score);
  c.require(std::isfinite(g.region_radius_px) && g.region_radius_px >= 0, "Geometry.region_radius_px", ">= 0",
            g.region_radius_px);
  c.require(std::isfinite(g.region_depth_m) && g.region_depth_m >= 0, "Geometry.region_depth_m", ">= 0",
            g.region_depth_m);
  c.require(std::isfinite(g.region_depth_ratio) && g.region_depth_ratio >= 0, "Geometry.region_depth_ratio",
            ">= 0", g.region_depth_ratio);
  c.require(g.region_steps >= 0 && g.region_steps <= 10, "Geometry.region_steps", "in [0, 10]",
            g.region_steps);
  c.require(std::isfinite(g.free_space_margin_m) && g.free_space_margin_m >= 0,
            "Geometry.free_space_margin_m", ">= 0 (0 = off)", g.free_space_margin_m);
  c.require(std::isfinite(g.free_space_ratio) && g.free_space_ratio >= 0, "Geometry.free_space_ratio", ">= 0",
            g.free_space_ratio);
  c.require(g.free_space_cull_run >= 1 && g.free_space_cull_run <= 8, "Geometry.free_space_cull_run",
            "in [1, 8]", g.free_space_cull_run);
  c.require(s.tracking.odometry_bridge_min_inliers >= 0, "Tracking.odometry_bridge_min_inliers", ">= 0 (0 = off)",
            s.tracking.odometry_bridge_min_inliers);
  c.require(std::isfinite(s.tracking.bridge_max_s) && s.tracking.bridge_max_s >= 0 && s.tracking.bridge_max_s <= 60,
            "Tracking.bridge_max_s", "in [0, 60] seconds (0 = off)", s.tracking.bridge_max_s);
  c.require(std::isfinite(s.tracking.reanchor_max_s) && s.tracking.reanchor_max_s >= 0 &&
                s.tracking.reanchor_max_s <= 60,
            "Tracking.reanchor_max_s", "in [0, 60] seconds (0 = off)", s.tracking.reanchor_max_s);
  c.require(std::isfinite(s.tracking.odometry_sigma_deg) && s.tracking.odometry_sigma_deg >= 0 &&
                s.tracking.odometry_sigma_deg <= 90,
            "Tracking.odometry_sigma_deg", "in [0, 90] degrees (0 = off)", s.tracking.odometry_sigma_deg);
  c.require(std::isfinite(s.tracking.keyframe_reference_ratio) && s.tracking.keyframe_reference_ratio > 0 &&
                s.tracking.keyframe_reference_ratio <= 1,
            "Tracking.keyframe_reference_ratio", "in (0, 1]", s.tracking.keyframe_reference_ratio);
  c.require(std::isfinite(s.tracking.bridge_min_people_share) && s.tracking.bridge_min_people_share >= 0 &&
                s.tracking.bridge_min_people_share <= 1,
            "Tracking.bridge_min_people_share", "in [0, 1]", s.tracking.bridge_min_people_share);
  c.require(std::isfinite(s.ground.keyframe_sigma) && s.ground.keyframe_sigma > 0 && s.ground.keyframe_sigma <= 1,
            "Ground.keyframe_sigma", "in (0, 1] (relative to the camera's height)", s.ground.keyframe_sigma);
  const auto& b = s.feature_budget;
  if (b.thresholds.empty()) c.fail("FeatureBudget.thresholds", "must not be empty");
  for (std::size_t i = 0; i < b.thresholds.size(); ++i) {
    c.require(b.thresholds[i] >= 0 && b.thresholds[i] <= 1, "FeatureBudget.thresholds", "fractions in [0, 1]",
              b.thresholds[i]);
    if (i > 0)
      c.require(b.thresholds[i] > b.thresholds[i - 1], "FeatureBudget.thresholds", "strictly increasing",
                b.thresholds[i]);
  }
  if (b.factors.size() != b.thresholds.size() + 1)
    c.fail("FeatureBudget.factors", "must have one more entry than FeatureBudget.thresholds (" +
                                        std::to_string(b.thresholds.size() + 1) + "), got " +
                                        std::to_string(b.factors.size()));
  for (const double f : b.factors) {
    c.positive(f, "FeatureBudget.factors");
    c.require(f <= kMaxBudgetFactor, "FeatureBudget.factors", "<= 10", f);
  }
  c.require(b.area == "sum" || b.area == "union", "FeatureBudget.area", "\"sum\" or \"union\"",
            "\"" + b.area + "\"");
  const auto& format = s.output.trajectory_format;
  c.require(format == "tum" || format == "kitti" || format == "euroc", "Output.trajectory_format",
            "\"tum\", \"kitti\" or \"euroc\"", "\"" + format + "\"");
}

std::string size_text(int width, int height) { return std::to_string(width) + "x" + std::to_string(height); }

}  // namespace

void check_image_size(const Settings& settings, cv::Size image, const std::string& image_path) {
  const auto& cam = settings.camera;
  if (cam.width <= 0 || cam.height <= 0) return;
  if (image.width == cam.width && image.height == cam.height) return;
  const std::string file = settings.path.empty() ? std::string("settings") : clip_text(settings.path);
  throw input_error(clip_text(image_path), "image is " + size_text(image.width, image.height) +
                                               ", but the settings " + file + " give Camera.width/height " +
                                               size_text(cam.width, cam.height) +
                                               " (settings for another camera?)");
}

void Settings::check(SensorKind sensor) const {
  const Checker c(path);
  check_camera(c, camera, sensor);
  c.positive(th_depth, "ThDepth");  // required (checked at load) only for stereo / RGB-D; defaults are valid
  c.positive(depth_map_factor, "DepthMapFactor");
  check_orb(c, orb);
  if (rectification) check_rectification(c, *rectification, camera);
  check_own_sections(c, *this);
}

}  // namespace crowdslam::io
