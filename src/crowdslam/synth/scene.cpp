#include "crowdslam/synth/scene.h"

#include <cmath>

#include "crowdslam/synth/trajectory_gen.h"

namespace crowdslam::synth {
namespace {

using V3 = Eigen::Vector3d;

// Lambertian shade of a face with the given normal under a fixed light from above.
double shade_for(const V3& normal) {
  const V3 light = V3(0.3, 0.5, 0.8).normalized();
  return 0.72 + 0.28 * std::max(0.0, normal.dot(light));
}

// Texel size of a face of the box (width along the face's u axis, height along v).
cv::Size face_size(const Box& box, int face) {
  const V3 size = 2.0 * box.half * kTexelsPerMetre;
  const auto px = [](double v) { return std::max(8, static_cast<int>(std::ceil(v)) + 1); };
  switch (face / 2) {
    case 0: return {px(size.y()), px(size.z())};
    case 1: return {px(size.x()), px(size.z())};
    default: return {px(size.x()), px(size.y())};
  }
}

}  // namespace

Scene Scene::build(const SynthOptions& options) {
  options.check();
  Scene scene;
  scene.options_ = options;
  scene.intrinsics_ = intrinsics_for(options.width, options.height);
  scene.trajectory_ = generate_trajectory(options.trajectory, options.frames, options.seed);
  const std::vector<cv::Mat> photos = load_photos(options.texture_dir);
  scene.photo_textures_ = !photos.empty();
  Rng rng(options.seed, 0x7e47);
  scene.add_room(rng, photos);
  // Obstacles near the walls; the middle of the room stays free for the camera and the people.
  scene.add_obstacle({1.7, 1.3, 0.0}, {2.1, 1.7, 3.0}, rng, photos);        // pillar
  scene.add_obstacle({-2.2, -1.8, 0.0}, {-1.85, -1.45, 3.0}, rng, photos);  // pillar
  scene.add_obstacle({-0.3, 2.1, 0.0}, {0.9, 2.5, 1.8}, rng, photos);       // cabinet against +y wall
  scene.add_obstacle({2.1, -2.2, 0.0}, {2.7, -1.6, 0.6}, rng, photos);      // crate
  scene.add_obstacle({2.25, -2.05, 0.6}, {2.65, -1.65, 1.0}, rng, photos);  // crate on the crate
  scene.add_obstacle({-2.85, -0.25, 0.0}, {-2.35, 0.65, 0.5}, rng, photos); // low box at -x wall
  // Table: top and four legs.
  const V3 table_min(-2.5, 1.3, 0.0);
  const V3 table_max(-1.3, 2.0, 0.75);
  scene.add_obstacle({table_min.x(), table_min.y(), 0.7}, table_max, rng, photos);
  for (int i = 0; i < 4; ++i) {
    const double x = (i & 1) ? table_max.x() - 0.1 : table_min.x() + 0.05;
    const double y = (i & 2) ? table_max.y() - 0.1 : table_min.y() + 0.05;
    scene.add_obstacle({x, y, 0.0}, {x + 0.05, y + 0.05, 0.7}, rng, photos);
  }
  scene.add_obstacle({0.3, -2.45, 0.0}, {1.5, -1.9, 0.9}, rng, photos);  // sideboard at -y wall
  for (size_t i = 1; i < scene.static_boxes_.size(); ++i) {
    const Box& b = scene.static_boxes_[i];
    scene.walk_area_.obstacles.emplace_back((b.center - b.half).head<2>(), (b.center + b.half).head<2>());
  }
  // Movers draw their textures from a stream of their own, so adding movers leaves the rest of a seed's
  // scene (textures, people's clothing) as it was; people walk around the floor each mover sweeps.
  Rng mover_rng(options.seed, 0x30e5);
  scene.add_movers(mover_rng, photos);
  scene.add_people(rng);
  return scene;
}

void Scene::texture_faces(Box& box, Rng& rng, const std::vector<cv::Mat>& photos) {
  for (int face = 0; face < 6; ++face) {
    const cv::Size size = face_size(box, face);
    Face& f = box.faces[face];
    f.texture = static_cast<int>(textures_.size());
    f.shade = shade_for(box.face_normal(face));
    textures_.emplace_back(make_collage(size.width, size.height, rng, photos));
  }
}

void Scene::add_room(Rng& rng, const std::vector<cv::Mat>& photos) {
  Box room = Box::axis_aligned({-3.0, -2.5, 0.0}, {3.0, 2.5, 3.0});
  room.inside = true;
  walk_area_.min_corner = {-3.0, -2.5};
  walk_area_.max_corner = {3.0, 2.5};
  texture_faces(room, rng, photos);
  static_boxes_.push_back(room);
}

void Scene::add_obstacle(const V3& min_corner, const V3& max_corner, Rng& rng,
                         const std::vector<cv::Mat>& photos) {
  Box box = Box::axis_aligned(min_corner, max_corner);
  texture_faces(box, rng, photos);
  static_boxes_.push_back(box);
}

void Scene::add_people(Rng& rng) {
  people_ = simulate_people(options_.people, trajectory_, walk_area_, options_.seed);
  const int width = static_cast<int>(std::ceil(2.0 * (kPersonWidthM + kPersonDepthM) * kTexelsPerMetre));
  const int height = static_cast<int>(std::ceil(kPersonHeightM * kTexelsPerMetre));
  for (size_t i = 0; i < people_.size(); ++i) {
    person_texture_.push_back(static_cast<int>(textures_.size()));
    textures_.emplace_back(make_clothing(width, height, rng));
  }
}

void Scene::add_movers(Rng& rng, const std::vector<cv::Mat>& photos) {
  movers_ = make_movers(options_.movers);
  for (const Mover& m : movers_) {
    Box box = m.box_at(0.0);
    texture_faces(box, rng, photos);
    mover_templates_.push_back(box);
    walk_area_.obstacles.push_back(m.footprint());
  }
}

std::vector<Box> Scene::mover_boxes(int frame) const {
  std::vector<Box> boxes;
  const double t = trajectory_.at(frame).timestamp_s - kFirstTimestampS;
  for (size_t i = 0; i < movers_.size(); ++i) {
    Box box = movers_[i].box_at(t);
    box.faces = mover_templates_[i].faces;
    for (int face = 0; face < 6; ++face) box.faces[face].shade = shade_for(box.face_normal(face));  // turns with it
    boxes.push_back(box);
  }
  return boxes;
}

std::vector<Box> Scene::moving_boxes(int frame) const {
  std::vector<Box> boxes = people_boxes(frame);
  for (Box& b : mover_boxes(frame)) boxes.push_back(std::move(b));
  return boxes;
}

std::vector<Box> Scene::people_boxes(int frame) const {
  std::vector<Box> boxes;
  for (size_t i = 0; i < people_.size(); ++i) {
    Box box = person_box(people_[i].states.at(frame), people_[i].id);
    // Faces wrap the clothing texture around the body: front, right, back, left; top shows the hair.
    const double w = kPersonWidthM * kTexelsPerMetre;
    const double d = kPersonDepthM * kTexelsPerMetre;
    const double u_offsets[6] = {w + d + w, w, w + d, 0.0, 0.0, 0.0};  // -x, +x, -y, +y, -z, +z
    for (int face = 0; face < 6; ++face) {
      box.faces[face].texture = person_texture_[i];
      box.faces[face].shade = shade_for(box.face_normal(face));
      box.faces[face].u_offset = u_offsets[face];
    }
    boxes.push_back(box);
  }
  return boxes;
}

geometry::SE3 Scene::right_world_from_cam(int frame) const {
  const geometry::SE3 left_from_right(Eigen::Quaterniond::Identity(), V3(kStereoBaselineM, 0.0, 0.0));
  return trajectory_.at(frame).world_from_cam * left_from_right;
}

}  // namespace crowdslam::synth
