#include "crowdslam/synth/options.h"

#include <cmath>

#include "crowdslam/util/error.h"

namespace crowdslam::synth {

TrajectoryKind parse_trajectory_kind(const std::string& name) {
  if (name == "loop") return TrajectoryKind::kLoop;
  if (name == "line") return TrajectoryKind::kLine;
  if (name == "sweep") return TrajectoryKind::kSweep;
  if (name == "handheld") return TrajectoryKind::kHandheld;
  throw InputError("--trajectory: unknown trajectory '" + name + "' (expected loop, line, sweep or handheld)");
}

std::string to_string(TrajectoryKind kind) {
  switch (kind) {
    case TrajectoryKind::kLoop: return "loop";
    case TrajectoryKind::kLine: return "line";
    case TrajectoryKind::kSweep: return "sweep";
    case TrajectoryKind::kHandheld: return "handheld";
  }
  return "loop";
}

CrowdProfile parse_crowd_profile(const std::string& name) {
  if (name == "auto") return CrowdProfile::kAuto;
  if (name == "walk") return CrowdProfile::kWalk;
  if (name == "passing") return CrowdProfile::kPassing;
  if (name == "standing") return CrowdProfile::kStanding;
  if (name == "near") return CrowdProfile::kNear;
  if (name == "blackout") return CrowdProfile::kBlackout;
  throw InputError("--crowd: unknown crowd profile '" + name +
                   "' (expected auto, walk, passing, standing, near or blackout)");
}

std::string to_string(CrowdProfile profile) {
  switch (profile) {
    case CrowdProfile::kAuto:
      return "auto";
    case CrowdProfile::kWalk:
      return "walk";
    case CrowdProfile::kPassing:
      return "passing";
    case CrowdProfile::kStanding:
      return "standing";
    case CrowdProfile::kNear:
      return "near";
    case CrowdProfile::kBlackout:
      return "blackout";
  }
  return "auto";
}

CrowdProfile SynthOptions::resolved_crowd() const {
  if (crowd != CrowdProfile::kAuto) return crowd;
  return sprite_dir.empty() ? CrowdProfile::kWalk : CrowdProfile::kPassing;
}

double SynthOptions::room_scale() const {
  const CrowdProfile profile = resolved_crowd();
  if (profile == CrowdProfile::kWalk) return 1.0;
  // Groups stand between the camera's path and the walls, where the small room has little floor.
  const int fits = profile == CrowdProfile::kStanding ? 8 : 12;
  return people <= fits ? 1.0 : std::sqrt(static_cast<double>(people) / fits);
}

void SynthOptions::check() const {
  if (frames < 1 || frames > 1000000) {
    throw InputError("--frames: must be between 1 and 1000000, got " + std::to_string(frames));
  }
  if (people < 0 || people > 50) {
    throw InputError("--people: must be between 0 and 50, got " + std::to_string(people));
  }
  if (movers < 0 || movers > 4) {
    throw InputError("--movers: must be between 0 and 4, got " + std::to_string(movers));
  }
  if (width < 16 || width > 8192) {
    throw InputError("--width: must be between 16 and 8192, got " + std::to_string(width));
  }
  if (height < 16 || height > 8192) {
    throw InputError("--height: must be between 16 and 8192, got " + std::to_string(height));
  }
  if (!std::isfinite(noise_depth_m) || noise_depth_m < 0.0 || noise_depth_m > 1.0) {
    throw InputError("--noise-depth: must be between 0 and 1 m, got " + std::to_string(noise_depth_m));
  }
}

Intrinsics intrinsics_for(int width, int height) {
  Intrinsics k;
  k.width = width;
  k.height = height;
  k.fx = 525.0 * width / 640.0;
  k.fy = k.fx;
  k.cx = (width - 1) / 2.0;
  k.cy = (height - 1) / 2.0;
  return k;
}

}  // namespace crowdslam::synth
