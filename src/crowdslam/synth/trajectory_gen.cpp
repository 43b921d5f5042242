#include "crowdslam/synth/trajectory_gen.h"

#include <algorithm>
#include <cmath>

#include "crowdslam/geometry/angles.h"
#include "crowdslam/synth/rng.h"

namespace crowdslam::synth {
namespace {

using geometry::kPi;
constexpr double kTwoPi = 2.0 * kPi;

struct PoseParams {
  Eigen::Vector3d position;
  double yaw = 0.0;
  double pitch = 0.0;
  double roll = 0.0;
};

// Closed loop: phase runs 0..1 over the sequence (several laps for long sequences).
PoseParams loop_params(double phase, int laps) {
  const double theta = kTwoPi * laps * phase;
  PoseParams p;
  p.position = {0.9 * std::cos(theta), 0.7 * std::sin(theta), 1.45 + 0.08 * std::sin(2.0 * theta)};
  p.yaw = theta + 0.45;  // outwards, a little towards the direction of motion
  p.pitch = -0.2 + 0.05 * std::sin(3.0 * theta);
  p.roll = 0.03 * std::sin(2.0 * theta);
  return p;
}

// Sum of smooth sinusoids whose frequencies are whole harmonics of the sequence (so phase 0 and 1 agree),
// with frequencies near 0.5-2 Hz.
class Shake {
 public:
  Shake(std::uint64_t seed, int frames) {
    Rng rng(seed, 0x5a4b);
    const double duration_s = std::max(1, frames - 1) / kFps;
    for (auto& channel : channels_) {
      for (auto& h : channel) {
        h.harmonic = std::max(1.0, std::round(rng.uniform(0.5, 2.0) * duration_s));
        h.phase = rng.uniform(0.0, kTwoPi);
        h.amplitude = rng.uniform(0.5, 1.0);
      }
    }
  }
  // Channel value in [-1, 1]-ish.
  double at(int channel, double phase) const {
    double sum = 0.0;
    for (const auto& h : channels_[channel]) sum += h.amplitude * std::sin(kTwoPi * h.harmonic * phase + h.phase);
    return sum / 2.0;
  }

 private:
  struct Harmonic {
    double harmonic = 1.0;
    double phase = 0.0;
    double amplitude = 0.0;
  };
  std::array<std::array<Harmonic, 3>, 6> channels_{};
};

PoseParams params_at(TrajectoryKind kind, int frame, int frames, const Shake& shake) {
  const double t = frame / kFps;
  const double phase = frames > 1 ? static_cast<double>(frame) / (frames - 1) : 0.0;
  const int laps = std::max(1, static_cast<int>(std::lround((frames - 1) / 300.0)));
  switch (kind) {
    case TrajectoryKind::kLoop: return loop_params(phase, laps);
    case TrajectoryKind::kHandheld: {
      PoseParams p = loop_params(phase, laps);
      p.position += 0.02 * Eigen::Vector3d(shake.at(0, phase), shake.at(1, phase), shake.at(2, phase));
      p.yaw += 0.02 * shake.at(3, phase);
      p.pitch += 0.015 * shake.at(4, phase);
      p.roll += 0.015 * shake.at(5, phase);
      return p;
    }
    case TrajectoryKind::kLine: {
      PoseParams p;
      p.position = {-1.0 * std::cos(kTwoPi * t / 12.0), -0.4, 1.4 + 0.05 * std::sin(kTwoPi * t / 5.0)};
      p.yaw = kPi / 2.0 + 0.1 * std::sin(kTwoPi * t / 7.0);
      p.pitch = -0.08;
      return p;
    }
    case TrajectoryKind::kSweep: {
      // Pans towards the side it moves to, so the walls it looks at stay within ~3.5 m.
      const double swing = std::sin(kTwoPi * t / 9.0);
      PoseParams p;
      p.position = {0.6 * swing, 0.2 + 0.2 * std::sin(kTwoPi * t / 13.0), 1.5};
      p.yaw = kPi / 2.0 - (70.0 * kPi / 180.0) * swing;
      p.pitch = -0.12 + 0.06 * std::sin(kTwoPi * t / 6.0);
      return p;
    }
  }
  return {};
}

}  // namespace

geometry::SE3 look_pose(const Eigen::Vector3d& position, double yaw, double pitch, double roll) {
  const Eigen::Vector3d forward(std::cos(yaw) * std::cos(pitch), std::sin(yaw) * std::cos(pitch),
                                std::sin(pitch));
  const Eigen::Vector3d right = forward.cross(Eigen::Vector3d::UnitZ()).normalized();
  const Eigen::Vector3d down = forward.cross(right);
  geometry::Mat3 world_from_cam_rotation;
  world_from_cam_rotation << right, down, forward;
  const Eigen::AngleAxisd roll_about_view(roll, Eigen::Vector3d::UnitZ());
  return geometry::SE3(geometry::Mat3(world_from_cam_rotation * roll_about_view.toRotationMatrix()), position);
}

io::Trajectory generate_trajectory(TrajectoryKind kind, int frames, std::uint64_t seed) {
  const Shake shake(seed, frames);
  io::Trajectory trajectory;
  trajectory.reserve(frames);
  for (int i = 0; i < frames; ++i) {
    const PoseParams p = params_at(kind, i, frames, shake);
    trajectory.push_back({timestamp_of(i), look_pose(p.position, p.yaw, p.pitch, p.roll)});
  }
  const bool closed = kind == TrajectoryKind::kLoop || kind == TrajectoryKind::kHandheld;
  if (closed && frames > 1) trajectory.back().world_from_cam = trajectory.front().world_from_cam;  // exact
  return trajectory;
}

}  // namespace crowdslam::synth
