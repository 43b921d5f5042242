#pragma once
// Walking people of the synthetic scene: upright boxes (0.45 x 0.3 x 1.75 m) moving on piecewise-linear
// paths over the floor at 0.5-1.2 m/s. They turn at the room bounds, around obstacles and each other,
// and keep at least ~0.7 m between their body and the camera centre (looking a little ahead in time).
#include <cstdint>
#include <vector>

#include "crowdslam/io/trajectory.h"
#include "crowdslam/synth/box.h"

namespace crowdslam::synth {

constexpr double kPersonWidthM = 0.45;
constexpr double kPersonDepthM = 0.30;
constexpr double kPersonHeightM = 1.75;
constexpr double kMinCameraClearanceM = 0.7;

// The floor area people may use: room bounds and obstacle footprints (x/y min/max), metres.
struct WalkArea {
  Eigen::Vector2d min_corner{-3.0, -2.5};
  Eigen::Vector2d max_corner{3.0, 2.5};
  std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> obstacles;  // (min, max) footprints
};

struct PersonState {
  Eigen::Vector2d position = Eigen::Vector2d::Zero();
  double body_yaw = 0.0;  // direction the person faces (radians, about z)
};

// What a person does (crowd.h): walk about, stand in a group, cross close in front of the camera, or
// belong to the group that blacks out the view.
enum class PersonRole { kWalker, kGroup, kNear, kBlackout };
const char* to_string(PersonRole role);

struct PersonTrack {
  int id = 0;  // 1-based
  PersonRole role = PersonRole::kWalker;
  double speed_mps = 0.0;
  std::vector<PersonState> states;  // one per frame
};

std::vector<PersonTrack> simulate_people(int count, const io::Trajectory& camera, const WalkArea& area,
                                         std::uint64_t seed);

// The person's box at a state (faces without textures).
Box person_box(const PersonState& state, int person_id);

// Horizontal distance from a point to a person's body box (0 inside).
double distance_to_person(const PersonState& state, const Eigen::Vector2d& point);

}  // namespace crowdslam::synth
