#pragma once
// Options of the synthetic sequence generator (`crowdslam synth`) and the camera they imply.
#include <cstdint>
#include <string>

namespace crowdslam::synth {

enum class TrajectoryKind { kLoop, kLine, kSweep, kHandheld };

// Parses "loop", "line", "sweep", "handheld"; throws InputError naming the value otherwise.
TrajectoryKind parse_trajectory_kind(const std::string& name);
std::string to_string(TrajectoryKind kind);

struct SynthOptions {
  int frames = 300;
  std::uint64_t seed = 1;
  int people = 0;
  int movers = 0;  // moving non-person objects (movers.h), 0..kMaxMovers
  bool stereo = false;
  TrajectoryKind trajectory = TrajectoryKind::kLoop;
  int width = 640;
  int height = 480;
  double noise_depth_m = 0.0;  // sigma of Gaussian noise added to the written depth images
  bool force = false;          // replace an existing non-empty output directory
  // Directory of photographs used as textures; empty = procedural textures only.
  std::string texture_dir = "/usr/share/doc/opencv-doc/examples/data";

  // Throws InputError naming the option and the bad value.
  void check() const;
};

// Pinhole camera: fx = fy = 525 at 640 px width (scaled with the width), principal point at the centre.
struct Intrinsics {
  double fx = 525.0;
  double fy = 525.0;
  double cx = 319.5;
  double cy = 239.5;
  int width = 640;
  int height = 480;
};
Intrinsics intrinsics_for(int width, int height);

constexpr double kFps = 30.0;
constexpr double kFirstTimestampS = 1.0;
constexpr double kStereoBaselineM = 0.12;
constexpr double kDepthFactor = 5000.0;  // depth PNG value = depth_m * kDepthFactor
constexpr double kMaxDepthM = 10.0;      // farther depth is written as 0 (missing)
constexpr const char* kGeneratorVersion = "crowdslam-synth 1";

inline double timestamp_of(int frame) { return kFirstTimestampS + frame / kFps; }

}  // namespace crowdslam::synth
