#pragma once
// The synthetic world: a 6 x 5 x 3 m room (x in [-3, 3], y in [-2.5, 2.5], z in [0, 3], z up) with
// pillars, tables, crates and a cabinet, photo-collage textures, the camera trajectory and walking people.
// A crowd of more than 12 people (profiles other than walk) gets a larger room, SynthOptions::room_scale()
// times as long and wide, its furniture and movers moved out with the walls.
//
// People are textured boxes, or, with person sprites (SynthOptions::sprite_dir), billboards that face
// the (left) camera, 1.55-1.9 m tall, each person with its own sprite (mirrored when it walks the other
// way than the person in the photograph did).
#include <vector>

#include "crowdslam/io/trajectory.h"
#include "crowdslam/synth/billboard.h"
#include "crowdslam/synth/box.h"
#include "crowdslam/synth/movers.h"
#include "crowdslam/synth/options.h"
#include "crowdslam/synth/people.h"
#include "crowdslam/synth/sprites.h"
#include "crowdslam/synth/textures.h"

namespace crowdslam::synth {

class Scene {
 public:
  // Builds everything the options ask for (textures, trajectory, people paths, sprites). Calls
  // options.check(); throws InputError naming the file when options.sprite_dir holds no usable sprites.
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
  // The people's textured boxes at a frame (person_id = 1..K); with sprites, the boxes are used for the
  // walking only and are not drawn.
  std::vector<Box> people_boxes(int frame) const;
  // With sprites: the people's billboards at a frame, facing the left camera; empty for box people.
  std::vector<Billboard> people_billboards(int frame) const;
  bool sprite_people() const { return !sprites_.empty(); }
  const std::vector<Sprite>& sprites() const { return sprites_; }
  // Per person (index = id - 1), with sprites: its sprite index and height.
  int person_sprite(int index) const { return person_sprite_.at(index); }
  double person_height_m(int index) const { return person_height_m_.at(index); }
  CrowdProfile crowd() const { return options_.resolved_crowd(); }
  // Blackout profile: first and last frame the group is planned to cover the view; {-1, -1} otherwise.
  std::pair<int, int> blackout_frames() const { return blackout_frames_; }
  const std::vector<Mover>& movers() const { return movers_; }
  // The movers' textured boxes at a frame (mover_id = 1..K).
  std::vector<Box> mover_boxes(int frame) const;
  // Everything drawn as a box that moves at a frame: people (box people only), then movers.
  std::vector<Box> moving_boxes(int frame) const;
  const std::vector<Texture>& textures() const { return textures_; }
  bool photo_textures() const { return photo_textures_; }
  const WalkArea& walk_area() const { return walk_area_; }

 private:
  Scene() = default;
  void add_room(Rng& rng, const std::vector<cv::Mat>& photos);
  // `anchor`: the floor point of the piece of furniture it belongs to, moved out with the walls.
  void add_obstacle(const Eigen::Vector3d& min_corner, const Eigen::Vector3d& max_corner, Rng& rng,
                    const std::vector<cv::Mat>& photos, const Eigen::Vector2d& anchor);
  void add_people(Rng& rng);
  void dress_people_with_sprites();
  void add_movers(Rng& rng, const std::vector<cv::Mat>& photos);
  void texture_faces(Box& box, Rng& rng, const std::vector<cv::Mat>& photos);

  SynthOptions options_;
  Intrinsics intrinsics_;
  io::Trajectory trajectory_;
  std::vector<Box> static_boxes_;
  std::vector<PersonTrack> people_;
  std::vector<int> person_texture_;  // texture index per person (box people)
  std::vector<Sprite> sprites_;
  std::vector<int> person_sprite_;                   // sprite index per person
  std::vector<double> person_height_m_;              // billboard height per person
  std::vector<std::vector<std::uint8_t>> mirrored_;  // per person, per frame: sprite mirrored
  std::pair<int, int> blackout_frames_{-1, -1};
  std::vector<Mover> movers_;
  std::vector<Box> mover_templates_;  // textured faces per mover (pose set per frame)
  std::vector<Texture> textures_;
  WalkArea walk_area_;
  bool photo_textures_ = false;
};

}  // namespace crowdslam::synth
