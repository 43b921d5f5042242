// load_settings, FeatureBudgetSettings::factor_for, operator==.
#include "crowdslam/io/settings.h"

#include "crowdslam/io/settings_reader.h"

namespace crowdslam::io {
namespace {

template <typename T>
void set_if(std::optional<T> value, T& target) {
  if (value) target = *value;
}

CameraSettings read_camera(const SettingsReader& r, SensorKind sensor) {
  CameraSettings c;
  c.fx = r.required_real("Camera.fx");
  c.fy = r.required_real("Camera.fy");
  c.cx = r.required_real("Camera.cx");
  c.cy = r.required_real("Camera.cy");
  c.k1 = r.required_real("Camera.k1");
  c.k2 = r.required_real("Camera.k2");
  c.p1 = r.required_real("Camera.p1");
  c.p2 = r.required_real("Camera.p2");
  set_if(r.real("Camera.k3"), c.k3);
  set_if(r.integer("Camera.width"), c.width);
  set_if(r.integer("Camera.height"), c.height);
  c.fps = r.required_real("Camera.fps");
  set_if(r.flag("Camera.RGB"), c.rgb);
  if (sensor != SensorKind::kMonocular) {
    c.bf = r.required_real("Camera.bf");
  } else {
    set_if(r.real("Camera.bf"), c.bf);
  }
  return c;
}

OrbSettings read_orb(const SettingsReader& r) {
  OrbSettings o;
  o.n_features = r.required_integer("ORBextractor.nFeatures");
  o.scale_factor = r.required_real("ORBextractor.scaleFactor");
  o.n_levels = r.required_integer("ORBextractor.nLevels");
  o.ini_th_fast = r.required_integer("ORBextractor.iniThFAST");
  o.min_th_fast = r.required_integer("ORBextractor.minThFAST");
  return o;
}

geometry::RectificationSide read_side(const SettingsReader& r, const std::string& side) {
  geometry::RectificationSide s;
  s.height = r.required_integer(side + ".height");
  s.width = r.required_integer(side + ".width");
  s.K = r.required_matrix(side + ".K");
  s.D = r.required_matrix(side + ".D");
  s.R = r.required_matrix(side + ".R");
  s.P = r.required_matrix(side + ".P");
  return s;
}

std::optional<geometry::StereoRectification> read_rectification(const SettingsReader& r) {
  bool any = false;
  for (const char* side : {"LEFT", "RIGHT"})
    for (const char* key : {".height", ".width", ".K", ".D", ".R", ".P"})
      any = any || r.has(std::string(side) + key);
  if (!any) return std::nullopt;
  return geometry::StereoRectification{read_side(r, "LEFT"), read_side(r, "RIGHT")};
}

void read_own_sections(const SettingsReader& r, Settings& s) {
  set_if(r.text("Detector.model_cfg"), s.detector.model_cfg);
  set_if(r.text("Detector.model_weights"), s.detector.model_weights);
  set_if(r.integer("Detector.input_size"), s.detector.input_size);
  set_if(r.integer("Detector.input_width"), s.detector.input_width);
  set_if(r.integer("Detector.input_height"), s.detector.input_height);
  set_if(r.text("Detector.backend"), s.detector.backend);
  set_if(r.text("Detector.preprocess"), s.detector.preprocess);
  set_if(r.text("Detector.resize"), s.detector.resize);
  set_if(r.real("Detector.confidence"), s.detector.confidence);
  set_if(r.real("Detector.nms"), s.detector.nms);
  set_if(r.integer("Detector.person_class"), s.detector.person_class);
  if (const auto raw = r.flag("Detector.filter_before_nms")) s.detector.filter_before_nms = *raw;
  set_if(r.real("Detector.raw_box_max_area_ratio"), s.detector.raw_box_max_area_ratio);
  set_if(r.text("Detector.mode"), s.detector.mode);
  set_if(r.integer("Detector.latest_interval"), s.detector.latest_interval);
  set_if(r.flag("Detector.tracker"), s.detector.tracker);
  set_if(r.real("Detector.track_iou"), s.detector.track_iou);
  set_if(r.integer("Detector.track_min_hits"), s.detector.track_min_hits);
  set_if(r.integer("Detector.track_max_misses"), s.detector.track_max_misses);
  set_if(r.real("Detector.track_confirm_confidence"), s.detector.track_confirm_confidence);
  set_if(r.flag("PeopleFilter.enabled"), s.people_filter.enabled);
  set_if(r.text("PeopleFilter.mode"), s.people_filter.mode);
  set_if(r.real("PeopleFilter.margin_px"), s.people_filter.margin_px);
  set_if(r.real("PeopleFilter.depth_margin_m"), s.people_filter.depth_margin_m);
  set_if(r.flag("PeopleFilter.silhouettes"), s.people_filter.silhouettes);
  set_if(r.real("PeopleFilter.segment_from_m"), s.people_filter.segment_from_m);
  set_if(r.text("PeopleFilter.right_image"), s.people_filter.right_image);
  set_if(r.text("PeopleFilter.static_in_boxes"), s.people_filter.static_in_boxes);
  set_if(r.integer("PeopleFilter.static_check_below"), s.people_filter.static_check_below);
  set_if(r.real("PeopleFilter.flat_box_margin_m"), s.people_filter.flat_box_margin_m);
  set_if(r.flag("Geometry.dynamic_check"), s.geometry.dynamic_check);
  set_if(r.real("Geometry.moving_factor"), s.geometry.moving_factor);
  set_if(r.real("Geometry.certain_factor"), s.geometry.certain_factor);
  set_if(r.integer("Geometry.dynamic_score"), s.geometry.dynamic_score);
  set_if(r.integer("Geometry.cull_score"), s.geometry.cull_score);
  set_if(r.real("Geometry.region_radius_px"), s.geometry.region_radius_px);
  set_if(r.real("Geometry.region_depth_m"), s.geometry.region_depth_m);
  set_if(r.real("Geometry.region_depth_ratio"), s.geometry.region_depth_ratio);
  set_if(r.real("Geometry.free_space_margin_m"), s.geometry.free_space_margin_m);
  set_if(r.real("Geometry.free_space_ratio"), s.geometry.free_space_ratio);
  set_if(r.integer("Geometry.region_steps"), s.geometry.region_steps);
  set_if(r.integer("Geometry.free_space_cull_run"), s.geometry.free_space_cull_run);
  set_if(r.integer("Tracking.odometry_bridge_min_inliers"), s.tracking.odometry_bridge_min_inliers);
  set_if(r.real("Tracking.bridge_max_s"), s.tracking.bridge_max_s);
  set_if(r.real("Tracking.reanchor_max_s"), s.tracking.reanchor_max_s);
  set_if(r.real("Tracking.odometry_sigma_deg"), s.tracking.odometry_sigma_deg);
  set_if(r.real("Tracking.keyframe_reference_ratio"), s.tracking.keyframe_reference_ratio);
  set_if(r.real("Tracking.bridge_min_people_share"), s.tracking.bridge_min_people_share);
  set_if(r.flag("Ground.enabled"), s.ground.enabled);
  set_if(r.real("Ground.keyframe_sigma"), s.ground.keyframe_sigma);
  set_if(r.flag("FeatureBudget.enabled"), s.feature_budget.enabled);
  set_if(r.reals("FeatureBudget.thresholds"), s.feature_budget.thresholds);
  set_if(r.reals("FeatureBudget.factors"), s.feature_budget.factors);
  set_if(r.text("FeatureBudget.area"), s.feature_budget.area);
  set_if(r.text("Output.trajectory_format"), s.output.trajectory_format);
}

bool same_matrix(const cv::Mat& a, const cv::Mat& b) {
  if (a.empty() || b.empty()) return a.empty() && b.empty();
  return a.size() == b.size() && a.type() == b.type() && cv::norm(a, b, cv::NORM_INF) == 0.0;
}

bool same_side(const geometry::RectificationSide& a, const geometry::RectificationSide& b) {
  return a.width == b.width && a.height == b.height && same_matrix(a.K, b.K) && same_matrix(a.D, b.D) &&
         same_matrix(a.R, b.R) && same_matrix(a.P, b.P);
}

bool same_rectification(const std::optional<geometry::StereoRectification>& a,
                        const std::optional<geometry::StereoRectification>& b) {
  if (!a || !b) return !a && !b;
  return same_side(a->left, b->left) && same_side(a->right, b->right);
}

}  // namespace

double FeatureBudgetSettings::factor_for(double people_area_fraction) const {
  if (thresholds.empty() || factors.empty()) return 1.0;
  if (people_area_fraction <= thresholds.front()) return factors.front();
  for (std::size_t i = 1; i < thresholds.size() && i < factors.size(); ++i)
    if (people_area_fraction < thresholds[i]) return factors[i];
  return factors.back();
}

Settings load_settings(const std::string& path, SensorKind sensor) {
  const SettingsReader r(path);
  Settings s;
  s.path = path;
  s.camera = read_camera(r, sensor);
  if (sensor != SensorKind::kMonocular) {
    s.th_depth = r.required_real("ThDepth");
  } else {
    set_if(r.real("ThDepth"), s.th_depth);
  }
  if (sensor == SensorKind::kRgbd) {
    s.depth_map_factor = r.required_real("DepthMapFactor");
  } else {
    set_if(r.real("DepthMapFactor"), s.depth_map_factor);
  }
  s.has_depth_map_factor = r.has("DepthMapFactor");
  s.has_baseline = r.has("Camera.bf");
  s.orb = read_orb(r);
  s.rectification = read_rectification(r);
  read_own_sections(r, s);
  s.check(sensor);
  return s;
}

bool operator==(const Settings& a, const Settings& b) {
  const auto& ca = a.camera;
  const auto& cb = b.camera;
  const bool camera = ca.fx == cb.fx && ca.fy == cb.fy && ca.cx == cb.cx && ca.cy == cb.cy &&
                      ca.k1 == cb.k1 && ca.k2 == cb.k2 && ca.p1 == cb.p1 && ca.p2 == cb.p2 &&
                      ca.k3 == cb.k3 && ca.width == cb.width && ca.height == cb.height && ca.bf == cb.bf &&
                      ca.fps == cb.fps && ca.rgb == cb.rgb;
  const bool orb = a.orb.n_features == b.orb.n_features && a.orb.scale_factor == b.orb.scale_factor &&
                   a.orb.n_levels == b.orb.n_levels && a.orb.ini_th_fast == b.orb.ini_th_fast &&
                   a.orb.min_th_fast == b.orb.min_th_fast;
  const auto& da = a.detector;
  const auto& db = b.detector;
  const bool detector = da.model_cfg == db.model_cfg && da.model_weights == db.model_weights &&
                        da.input_size == db.input_size && da.input_width == db.input_width &&
                        da.input_height == db.input_height && da.backend == db.backend &&
                        da.preprocess == db.preprocess && da.resize == db.resize &&
                        da.confidence == db.confidence && da.nms == db.nms &&
                        da.person_class == db.person_class && da.filter_before_nms == db.filter_before_nms &&
                        da.raw_box_max_area_ratio == db.raw_box_max_area_ratio;
  const bool people = a.people_filter.enabled == b.people_filter.enabled &&
                      a.people_filter.mode == b.people_filter.mode &&
                      a.people_filter.margin_px == b.people_filter.margin_px &&
                      a.people_filter.depth_margin_m == b.people_filter.depth_margin_m &&
                      a.people_filter.silhouettes == b.people_filter.silhouettes &&
                      a.people_filter.segment_from_m == b.people_filter.segment_from_m &&
                      a.people_filter.right_image == b.people_filter.right_image &&
                      a.people_filter.flat_box_margin_m == b.people_filter.flat_box_margin_m;
  const auto& ga = a.geometry;
  const auto& gb = b.geometry;
  const bool geometry =
      ga.dynamic_check == gb.dynamic_check && ga.moving_factor == gb.moving_factor &&
      ga.certain_factor == gb.certain_factor && ga.dynamic_score == gb.dynamic_score &&
      ga.cull_score == gb.cull_score && ga.region_radius_px == gb.region_radius_px &&
      ga.region_depth_m == gb.region_depth_m && ga.region_depth_ratio == gb.region_depth_ratio &&
      ga.region_steps == gb.region_steps && ga.free_space_margin_m == gb.free_space_margin_m &&
      ga.free_space_ratio == gb.free_space_ratio && ga.free_space_cull_run == gb.free_space_cull_run;
  const bool budget = a.feature_budget.enabled == b.feature_budget.enabled &&
                      a.feature_budget.thresholds == b.feature_budget.thresholds &&
                      a.feature_budget.factors == b.feature_budget.factors &&
                      a.feature_budget.area == b.feature_budget.area;
  const bool tracking = a.tracking.odometry_bridge_min_inliers == b.tracking.odometry_bridge_min_inliers &&
                        a.tracking.bridge_max_s == b.tracking.bridge_max_s &&
                        a.tracking.bridge_min_people_share == b.tracking.bridge_min_people_share &&
                        a.tracking.reanchor_max_s == b.tracking.reanchor_max_s &&
                        a.tracking.odometry_sigma_deg == b.tracking.odometry_sigma_deg &&
                        a.tracking.keyframe_reference_ratio == b.tracking.keyframe_reference_ratio;
  const bool ground = a.ground.enabled == b.ground.enabled && a.ground.keyframe_sigma == b.ground.keyframe_sigma;
  return camera && orb && detector && people && geometry && tracking && ground && budget && a.th_depth == b.th_depth &&
         a.depth_map_factor == b.depth_map_factor && a.has_depth_map_factor == b.has_depth_map_factor &&
         a.has_baseline == b.has_baseline && a.output.trajectory_format == b.output.trajectory_format &&
         same_rectification(a.rectification, b.rectification);
}

void apply_rectification(Settings& settings, const geometry::StereoRectification& rectification) {
  const cv::Mat& p = rectification.left.P;
  auto& c = settings.camera;
  c.fx = p.at<double>(0, 0);
  c.fy = p.at<double>(1, 1);
  c.cx = p.at<double>(0, 2);
  c.cy = p.at<double>(1, 2);
  c.k1 = c.k2 = c.p1 = c.p2 = c.k3 = 0.0;
  c.bf = -rectification.right.P.at<double>(0, 3);
  c.width = rectification.left.width;
  c.height = rectification.left.height;
  settings.rectification = rectification;
}

}  // namespace crowdslam::io
