#pragma once
// The synthetic world: a 6 x 5 x 3 m room (x in [-3, 3], y in [-2.5, 2.5], z in [0, 3], z up) with
// pillars, tables, crates and a cabinet, photo-collage textures, the camera trajectory and walking people.
#include <vector>

#include "crowdslam/io/trajectory.h"
#include "crowdslam/synth/box.h"
#include "crowdslam/synth/movers.h"
#include "crowdslam/synth/options.h"
#include "crowdslam/synth/people.h"
#include "crowdslam/synth/textures.h"

namespace crowdslam::synth {

class Scene {
 public:
  // Builds everything the options ask for (textures, trajectory, people paths). Calls options.check().
  static Scene build(const SynthOptions& options);

  const SynthOptions& options() const { return options_; }
  const Intrinsics& intrinsics() const { return intrinsics_; }
  int frame_count() const { return static_cast<int>(trajectory_.size()); }
  // world_from_cam of the left / RGB camera.
  const io::Trajectory& trajectory() const { return trajectory_; }
  // world_from_cam of the right stereo camera (baseline kStereoBaselineM along the camera x axis).
  geometry::SE3 right_world_from_cam(int frame) const;

  // The room is static_boxes()[0]; the others are obstacles.
  const std::vector<Box>& static_boxes() const { return static_boxes_; }
  const std::vector<PersonTrack>& people() const { return people_; }
  // The people's textured boxes at a frame (person_id = 1..K).
  std::vector<Box> people_boxes(int frame) const;
  const std::vector<Mover>& movers() const { return movers_; }
  // The movers' textured boxes at a frame (mover_id = 1..K).
  std::vector<Box> mover_boxes(int frame) const;
  // Everything that moves at a frame: people, then movers.
  std::vector<Box> moving_boxes(int frame) const;
  const std::vector<Texture>& textures() const { return textures_; }
  bool photo_textures() const { return photo_textures_; }
  const WalkArea& walk_area() const { return walk_area_; }

 private:
  Scene() = default;
  void add_room(Rng& rng, const std::vector<cv::Mat>& photos);
  void add_obstacle(const Eigen::Vector3d& min_corner, const Eigen::Vector3d& max_corner, Rng& rng,
                    const std::vector<cv::Mat>& photos);
  void add_people(Rng& rng);
  void add_movers(Rng& rng, const std::vector<cv::Mat>& photos);
  void texture_faces(Box& box, Rng& rng, const std::vector<cv::Mat>& photos);

  SynthOptions options_;
  Intrinsics intrinsics_;
  io::Trajectory trajectory_;
  std::vector<Box> static_boxes_;
  std::vector<PersonTrack> people_;
  std::vector<int> person_texture_;  // texture index per person
  std::vector<Mover> movers_;
  std::vector<Box> mover_templates_;  // textured faces per mover (pose set per frame)
  std::vector<Texture> textures_;
  WalkArea walk_area_;
  bool photo_textures_ = false;
};

}  // namespace crowdslam::synth
