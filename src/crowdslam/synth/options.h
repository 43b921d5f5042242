#pragma once
// Options of the synthetic sequence generator (`crowdslam synth`) and the camera they imply.
#include <cstdint>
#include <string>

namespace crowdslam::synth {

enum class TrajectoryKind { kLoop, kLine, kSweep, kHandheld };

// Parses "loop", "line", "sweep", "handheld"; throws InputError naming the value otherwise.
TrajectoryKind parse_trajectory_kind(const std::string& name);
std::string to_string(TrajectoryKind kind);

// How the people behave (people.h, crowd.h):
//   walk:     the first walkers (piecewise-linear walks, half towards the view), >= ~1 m from the camera;
//   passing:  walkers that mostly cross the view, passing each other, stopping for 1-4 s now and then;
//   standing: groups of 2-4 standing together (three quarters of the people), a few walkers;
//   near:     a third of the people cross close in front of the camera (down to ~0.4 m), the rest pass;
//   blackout: a dense group walks right in front of the camera once, covering the view for ~1.5 s;
//   auto:     passing with person sprites, walk with box people (the behaviour before sprites).
enum class CrowdProfile { kAuto, kWalk, kPassing, kStanding, kNear, kBlackout };
// Parses the names above; throws InputError naming --crowd and the value otherwise.
CrowdProfile parse_crowd_profile(const std::string& name);
std::string to_string(CrowdProfile profile);

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
  // Directory of person sprites (sprites.h: sprites.json and its PNGs); empty = people are textured boxes.
  // The library never looks for a default; `crowdslam synth` resolves one (resolve_sprite_dir).
  std::string sprite_dir;
  CrowdProfile crowd = CrowdProfile::kAuto;
  // The same sequence (room, camera path, every person's path) rendered without the people: the empty-room
  // baseline of a crowd (--hide-people). people_gt.txt is then empty.
  bool hide_people = false;

  // The profile `crowd` stands for: kAuto -> kPassing with sprites, kWalk without.
  CrowdProfile resolved_crowd() const;
  // Room size factor along x and y: 1 (6 x 5 m) for the walk profile and up to 12 people (standing: 8);
  // beyond, sqrt(people / 12) (standing: sqrt(people / 8)), so a crowd of 30 has room to walk
  // (9.5 x 7.9 m) and groups room to stand.
  double room_scale() const;

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
