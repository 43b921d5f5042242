#pragma once
// ORB-SLAM2-style settings files (YAML read with cv::FileStorage, first line "%YAML:1.0"), plus our own
// sections (Detector, PeopleFilter, FeatureBudget, Output) which take defaults when absent.
//
// ORB-SLAM2 keys. Required: Camera.fx/fy/cx/cy, Camera.k1/k2/p1/p2, Camera.fps, ORBextractor.nFeatures/
// scaleFactor/nLevels/iniThFAST/minThFAST; for stereo and RGB-D also Camera.bf and ThDepth; for RGB-D also
// DepthMapFactor. Optional: Camera.k3 (0), Camera.width/height (0 = unknown), Camera.RGB (1), and the
// stereo rectification LEFT.height/width/K/D/R/P + RIGHT.* (all twelve or none; matrices as opencv-matrix).
// As in ORB-SLAM2, Camera.* describe the images SLAM works on: for stereo files with rectification
// those are the rectified images, so Camera.fx/fy/cx/cy must match LEFT.P and Camera.bf must match
// -RIGHT.P(0,3) (checked, 0.1% tolerance).
//
// Every missing or invalid value throws InputError "FILE: KEY: reason". A key set twice is an error
// "FILE:LINE: KEY: set twice (first on line N)"; an unknown key is a warning naming FILE:LINE and the key,
// with the closest known key as a suggestion; ORB-SLAM2/3 keys crowdslam does not use (Viewer.*,
// Camera.type, Camera.bFishEye, IMU.*, System.*, File.version, Tbc) are accepted silently (see
// settings_reader.h). Integers must fit in 32 bits ("ORBextractor.nFeatures: 1e20 is out of range for an
// integer"), and every value is checked against what the components that use it accept (FAST thresholds
// 1..254, at most 100000 features, ...), so no component rejects a value without naming file and key.
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "crowdslam/geometry/stereo_rectification.h"
#include "crowdslam/io/dataset.h"

namespace crowdslam::io {

struct CameraSettings {
  double fx = 0.0, fy = 0.0, cx = 0.0, cy = 0.0;
  double k1 = 0.0, k2 = 0.0, p1 = 0.0, p2 = 0.0, k3 = 0.0;
  int width = 0;    // 0 = not given
  int height = 0;   // 0 = not given
  double bf = 0.0;  // baseline (m) * fx; stereo and RGB-D
  double fps = 30.0;
  bool rgb = true;  // Camera.RGB: 1 = colour images are RGB ordered, 0 = BGR (ORB-SLAM2 meaning)
};

struct OrbSettings {
  int n_features = 1000;
  double scale_factor = 1.2;
  int n_levels = 8;
  int ini_th_fast = 20;
  int min_th_fast = 7;
};

struct DetectorSettings {
  std::string model_cfg;  // model name (body, coco, yolox, bytetrack), Darknet .cfg or .onnx (empty = body)
  std::string model_weights;  // Darknet .weights
  int input_size = 160;       // square network input, multiple of 32 (shorthand for width = height)
  int input_width = 0;        // with input_height: a non-square input, e.g. 416 x 256 (0 = input_size)
  int input_height = 0;
  std::string backend = "auto";  // auto | darknet | yolo-onnx | yolox (auto: the model's, else by extension)
  std::string preprocess = "auto";  // auto | darknet | yolox | bytetrack (auto: the model's / backend's)
  std::string resize = "auto";      // auto | stretch | letterbox (auto: the preprocessing's)
  double confidence = 0.2;
  double nms = 0.1;
  int person_class = 0;
  // Mask with the raw (pre-NMS) boxes (Crowd-SLAM). Unset: with depth or stereo yes (the depth check
  // gives back the background they cover), monocular no (nothing gives it back; in crowds the raw boxes'
  // union covers the background between people). docs/CROWDS.md#the-people-filter-and-the-feature-budget
  std::optional<bool> filter_before_nms;
  // Raw boxes over this many times the area of their NMS box are not used as masks (0 = all raw boxes,
  // as the paper); see people::raw_boxes_near_leaders.
  double raw_box_max_area_ratio = 2.0;
  // "every_frame": detect on every frame, the frame waits for its boxes; "latest": the detector takes the
  // newest frame when free, other frames get its boxes moved by the image flow (people/people_stage.h).
  std::string mode = "every_frame";
  // latest mode: a frame is offered to the detector only this many frames after the last one it took
  // (1 = whenever it is free); between detections the boxes move with the image flow.
  int latest_interval = 1;
  // Short-term box tracks (people/box_tracker.h) and their parameters.
  bool tracker = false;
  double track_iou = 0.3;
  int track_min_hits = 2;
  int track_max_misses = 2;
  double track_confirm_confidence = 0.5;
};

struct PeopleFilterSettings {
  bool enabled = true;
  std::string mode = "depth";  // "depth" (default: measured best on bonn_crowd) | "paper"
  double margin_px = 5.0;
  // "depth" mode: keypoints this far behind the person are kept. 0.5: bonn_crowd as with 1.0, and in
  // crowds close to the camera the background 0.5-1 m behind people is kept (docs/CROWDS.md).
  double depth_margin_m = 0.5;
  // "depth" mode: a kept keypoint whose 5 x 5 neighbourhood shows the person (their outline) is dropped too.
  bool silhouettes = true;
  // "depth" mode, RGB-D: a keypoint in a box more than this behind the person (and within the depth
  // margin) is kept when it is off the person's surface grown from the box over the depth image
  // (people/person_segment.h): a wall or plant close behind them, taken in by a loose box. 0 = off (the
  // default): 0.15 kept more background in the crowds but made the ATE of some worse (docs/CROWDS.md).
  double segment_from_m = 0;
  // Stereo: "matched" (default) drops a right keypoint only with its left match; "boxes" also drops the
  // stereo match of a kept left keypoint whose right coordinate falls in a (left-image) person box.
  std::string right_image = "matched";
  // Keypoints in boxes that match trusted static map points and agree with the pose help tracking when
  // the filtered frame tracks fewer than static_check_below points or fails (tracking/tracker.h,
  // box_keypoints.cpp): a false-positive box over most of the image, or background a person box hides,
  // then costs no tracking. Nothing in the map is made of them.
  // "auto" (default): with --sensor mono on a weak or failed frame, where a box hides the background
  // behind a person (no depth mode to keep it); with depth only on a frame the filtered keypoints fail on
  // (not within a second after a bridged frame). "monocular": with --sensor mono only; "always": every
  // sensor, weak or failed frames; "never". Measured in docs/CROWDS.md.
  std::string static_in_boxes = "auto";
  int static_check_below = 150;
  // RGB-D: a box whose torso region is not closer than the surface around the box by more than this is
  // flat (a poster, a wall photograph, a screen; people/box_depth.h) and filters nothing. 0 = off.
  double flat_box_margin_m = 0.2;
};

// Geometric dynamic check of tracked keypoints against the static map (tracking/dynamic_check.h).
struct GeometrySettings {
  bool dynamic_check = true;    // off: --geometry off or Geometry.dynamic_check: 0
  double moving_factor = 4.0;   // residual chi2 above this x the 95 % threshold counts as motion
  double certain_factor = 0.0;  // one observation above this x makes a keypoint dynamic (0 = never)
  int dynamic_score = 8;        // moving verdicts among a map point's last 8 that make its keypoints dynamic
  int cull_score = 8;           // moving verdicts among its last 8 at which it is culled
  double region_radius_px = 20.0;  // region growing radius at 640 px width
  double region_depth_m = 0.15;    // region growing depth tolerance (or region_depth_ratio x depth)
  double region_depth_ratio = 0.08;
  int region_steps = 2;
  // RGB-D free-space test (tracking/dynamic_check.h): a point the depth image sees through by more than
  // max(margin, ratio x z) gets a moving verdict; culled after free_space_cull_run of them in a row.
  double free_space_margin_m = 0.2;  // 0 = off
  double free_space_ratio = 0.1;
  int free_space_cull_run = 2;
};

// Tracking through views the map does not cover (tracking/tracker.h, TrackerOptions).
struct TrackingSettings {
  // RGB-D / stereo: inliers among the last frame's points, its depth points included, that let the
  // motion model track a frame seeing too few map points, and make it a keyframe (0 = off).
  int odometry_bridge_min_inliers = 50;
  // Occlusion bridge: a frame that fails while people took at least this share of its keypoints gets the
  // motion model's pose (state "bridged", not tracked) for up to bridge_max_s after the last tracked frame,
  // and no new map is started meanwhile (0 = off).
  double bridge_max_s = 3.0;
  double bridge_min_people_share = 0.5;
  // Monocular: lost in a grown map, a two-view map made where the camera is joins the same map, placed
  // and scaled by the motion before the loss, if it succeeds within reanchor_max_s (0 = off: a new map).
  double reanchor_max_s = 3.0;
  // RGB-D / stereo: local bundle adjustment keeps each keyframe near the pose tracking measured for it
  // relative to the keyframe before, with this rotation sigma in degrees (translation: the angle times
  // the keyframe's median depth); 0 = off, as ORB-SLAM.
  double odometry_sigma_deg = 0.3;
  // RGB-D / stereo: a keyframe is due when the frame tracks fewer than this share of its reference
  // keyframe's points (ORB-SLAM2: 0.75). Fewer keyframes cost less CPU; more measured better in crowds
  // (docs/PROFILE.md). Monocular keeps ORB-SLAM2's 0.9.
  double keyframe_reference_ratio = 0.9;
};

// A monocular camera that rides at a constant height above planar ground (on a car or a ground robot):
// global BA (the final one of a completed run, and those after loop closures) holds each keyframe's
// ground at one height, which takes out the scale drift of monocular mapping (geometry/ground_plane.h,
// docs/MAPPING.md). Not for handheld or flying cameras. Stereo and RGB-D have their scale and ignore it.
struct GroundSettings {
  bool enabled = false;
  double keyframe_sigma = 0.01;  // a keyframe's height sigma, relative to the map's ground height
};

struct FeatureBudgetSettings {
  bool enabled = true;
  std::vector<double> thresholds{0.0, 0.3, 0.6, 0.9, 0.95};
  std::vector<double> factors{1.0, 1.3, 1.5, 1.7, 1.9, 2.2};
  std::string area = "sum";  // "sum" of box areas (paper) or "union" of the boxes
  // Factor for the fraction of the image covered by people: a <= thresholds[0] -> factors[0],
  // a < thresholds[i] -> factors[i], else factors.back().
  [[nodiscard]] double factor_for(double people_area_fraction) const;
};

struct OutputSettings {
  std::string trajectory_format = "tum";  // "tum" | "kitti" | "euroc"
};

struct Settings {
  std::string path;  // the file read (not part of operator==)
  CameraSettings camera;
  double th_depth = 40.0;         // close/far threshold in multiples of the baseline (stereo, RGB-D)
  double depth_map_factor = 1.0;  // raw depth / factor = metres (RGB-D)
  OrbSettings orb;
  std::optional<geometry::StereoRectification> rectification;
  DetectorSettings detector;
  PeopleFilterSettings people_filter;
  GeometrySettings geometry;
  TrackingSettings tracking;
  GroundSettings ground;
  FeatureBudgetSettings feature_budget;
  OutputSettings output;
  // Which camera the file describes, whatever sensor it was loaded for: DepthMapFactor present = an
  // RGB-D camera; Camera.bf present = a camera with a baseline (stereo, or RGB-D's virtual baseline: a
  // stereo file has Camera.bf without DepthMapFactor). write_settings writes DepthMapFactor / Camera.bf
  // only when these are set. Part of operator==.
  bool has_depth_map_factor = false;
  bool has_baseline = false;

  // Validates every value for the sensor; throws InputError "PATH: KEY: reason".
  void check(SensorKind sensor) const;
};

// Throws InputError "IMAGE: image is WxH, but the settings FILE give Camera.width/height W0xH0" when
// the settings give both Camera.width and Camera.height and `image` differs. When they do not (0 = not
// given), nothing is checked here: the dataset then checks every frame against its first one
// (Dataset::load).
void check_image_size(const Settings& settings, cv::Size image, const std::string& image_path);

bool operator==(const Settings& a, const Settings& b);
inline bool operator!=(const Settings& a, const Settings& b) { return !(a == b); }

// Reads and checks a settings file. Keys required only for stereo / RGB-D (Camera.bf, ThDepth,
// DepthMapFactor) are enforced for that sensor.
Settings load_settings(const std::string& path, SensorKind sensor);

// Writes every key (ORB-SLAM2 names, our sections, rectification when present; DepthMapFactor and
// Camera.bf as has_depth_map_factor / has_baseline say) atomically; numbers with 17 significant digits,
// so load_settings(path, sensor) == settings. Checks nothing.
void write_settings(const std::string& path, const Settings& settings);

// Sets settings.rectification and Camera.* (fx, fy, cx, cy from LEFT.P, bf = -RIGHT.P(0,3), distortion
// zero, width and height of the rectified images).
void apply_rectification(Settings& settings, const geometry::StereoRectification& rectification);

}  // namespace crowdslam::io
