#pragma once
// Crowd profiles of the synthetic scene (SynthOptions::crowd; the walk profile is simulate_people in
// people.h):
//   passing:  walkers whose legs mostly cross the camera's view from one side to the other, so they pass
//             each other in front of it; a walker stops for 1-4 s about every 10 s;
//   standing: three quarters of the people stand in groups of 2-4 (on a circle, facing its centre, swaying
//             a little), placed where the camera passes by (within 3 m, no closer than 0.7 m to a
//             member); the others walk, stopping about every 5 s;
//   near:     a third of the people (at least one) cross close in front of the camera, down to
//             kNearCameraDistanceM; the others walk as in passing;
//   blackout: a group of up to 7 walks right in front of the camera (two rows, 0.5 and 0.85 m away) once,
//             covering the view for kBlackoutSeconds; before and after it stands where it entered and left
//             the view. The others walk as in passing.
// Walkers keep their centre >= kCrowdSpacingM from everybody else's and >= kWalkerCameraDistanceM (near
// crossers kNearCameraDistanceM) from the camera centre, looking up to 20 frames ahead, inside the room
// and around the obstacles; they wait when no step is allowed. Groups and the blackout group follow their
// script and do not give way (the blackout group stays inside the room but may touch furniture).
#include <cstdint>
#include <vector>

#include "crowdslam/synth/options.h"
#include "crowdslam/synth/people.h"

namespace crowdslam::synth {

constexpr double kCrowdSpacingM = 0.6;
constexpr double kWalkerCameraDistanceM = 1.0;
constexpr double kNearCameraDistanceM = 0.4;
constexpr double kBlackoutSeconds = 1.5;

struct Crowd {
  std::vector<PersonTrack> people;  // ids 1..count
  // Blackout profile: the frames during which the group is planned to cover the view (-1 when none).
  int blackout_first = -1;
  int blackout_last = -1;
};

// `profile` must not be kAuto or kWalk. Deterministic for a seed.
Crowd simulate_crowd(CrowdProfile profile, int count, const io::Trajectory& camera, const WalkArea& area,
                     std::uint64_t seed);

}  // namespace crowdslam::synth
