// The settings keys crowdslam knows: those load_settings reads and ORB-SLAM2/3 keys it accepts unused.
#include <algorithm>

#include "crowdslam/io/settings_reader.h"

namespace crowdslam::io {
namespace {

// ORB-SLAM2/3 keys of the published TUM/EuRoC/KITTI files that crowdslam has no use for (no viewer, no
// fisheye model, no IMU); accepted without a warning so those files work as they are.
const char* const kAcceptedKeys[] = {
    "Camera.type",      "Camera.bFishEye",   "File.version", "Camera.newWidth",
    "Camera.newHeight", "Camera.imageScale", "Tbc"};
const char* const kAcceptedPrefixes[] = {"Viewer.", "IMU.", "System."};

}  // namespace

const std::vector<std::string>& known_settings_keys() {
  static const std::vector<std::string> keys = [] {
    std::vector<std::string> k = {"Camera.fx",
                                  "Camera.fy",
                                  "Camera.cx",
                                  "Camera.cy",
                                  "Camera.k1",
                                  "Camera.k2",
                                  "Camera.p1",
                                  "Camera.p2",
                                  "Camera.k3",
                                  "Camera.width",
                                  "Camera.height",
                                  "Camera.fps",
                                  "Camera.bf",
                                  "Camera.RGB",
                                  "ThDepth",
                                  "DepthMapFactor",
                                  "ORBextractor.nFeatures",
                                  "ORBextractor.scaleFactor",
                                  "ORBextractor.nLevels",
                                  "ORBextractor.iniThFAST",
                                  "ORBextractor.minThFAST",
                                  "Detector.model_cfg",
                                  "Detector.model_weights",
                                  "Detector.input_size",
                                  "Detector.input_width",
                                  "Detector.input_height",
                                  "Detector.backend",
                                  "Detector.preprocess",
                                  "Detector.resize",
                                  "Detector.confidence",
                                  "Detector.nms",
                                  "Detector.person_class",
                                  "Detector.filter_before_nms",
                                  "Detector.raw_box_max_area_ratio",
                                  "Detector.mode",
                                  "Detector.latest_interval",
                                  "Detector.tracker",
                                  "Detector.track_iou",
                                  "Detector.track_min_hits",
                                  "Detector.track_max_misses",
                                  "Detector.track_confirm_confidence",
                                  "PeopleFilter.enabled",
                                  "PeopleFilter.mode",
                                  "PeopleFilter.margin_px",
                                  "PeopleFilter.depth_margin_m",
                                  "PeopleFilter.silhouettes",
                                  "PeopleFilter.segment_from_m",
                                  "PeopleFilter.right_image",
                                  "PeopleFilter.static_in_boxes",
                                  "PeopleFilter.static_check_below",
                                  "PeopleFilter.flat_box_margin_m",
                                  "Geometry.dynamic_check",
                                  "Geometry.moving_factor",
                                  "Geometry.certain_factor",
                                  "Geometry.dynamic_score",
                                  "Geometry.cull_score",
                                  "Geometry.region_radius_px",
                                  "Geometry.region_depth_m",
                                  "Geometry.region_depth_ratio",
                                  "Geometry.region_steps",
                                  "Geometry.free_space_margin_m",
                                  "Geometry.free_space_ratio",
                                  "Geometry.free_space_cull_run",
                                  "Tracking.odometry_bridge_min_inliers",
                                  "Tracking.bridge_max_s",
                                  "Tracking.bridge_min_people_share",
                                  "Tracking.reanchor_max_s",
                                  "Tracking.odometry_sigma_deg",
                                  "Tracking.keyframe_reference_ratio",
                                  "Ground.enabled",
                                  "Ground.keyframe_sigma",
                                  "FeatureBudget.enabled",
                                  "FeatureBudget.thresholds",
                                  "FeatureBudget.factors",
                                  "FeatureBudget.area",
                                  "Output.trajectory_format"};
    for (const char* side : {"LEFT", "RIGHT"})
      for (const char* key : {".height", ".width", ".K", ".D", ".R", ".P"})
        k.push_back(std::string(side) + key);
    return k;
  }();
  return keys;
}

bool is_accepted_settings_key(const std::string& key) {
  const auto& known = known_settings_keys();
  if (std::find(known.begin(), known.end(), key) != known.end()) return true;
  if (std::any_of(std::begin(kAcceptedKeys), std::end(kAcceptedKeys),
                  [&](const char* k) { return key == k; }))
    return true;
  return std::any_of(std::begin(kAcceptedPrefixes), std::end(kAcceptedPrefixes),
                     [&](const char* p) { return key.rfind(p, 0) == 0; });
}

}  // namespace crowdslam::io
