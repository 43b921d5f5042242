#include "crowdslam/synth/scene.h"

#include <algorithm>
#include <cmath>
#include <map>

#include "crowdslam/synth/crowd.h"
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
  if (!options.sprite_dir.empty()) scene.sprites_ = load_sprites(options.sprite_dir);
  scene.intrinsics_ = intrinsics_for(options.width, options.height);
  scene.trajectory_ = generate_trajectory(options.trajectory, options.frames, options.seed);
  const std::vector<cv::Mat> photos = load_photos(options.texture_dir);
  scene.photo_textures_ = !photos.empty();
  Rng rng(options.seed, 0x7e47);
  scene.add_room(rng, photos);
  // Obstacles near the walls; the middle of the room stays free for the camera and the people. In a larger
  // room each piece of furniture moves out with the walls (by its anchor, a floor point of it).
  const auto add = [&](const V3& lo, const V3& hi) {
    scene.add_obstacle(lo, hi, rng, photos, 0.5 * (lo + hi).head<2>());
  };
  add({1.7, 1.3, 0.0}, {2.1, 1.7, 3.0});        // pillar
  add({-2.2, -1.8, 0.0}, {-1.85, -1.45, 3.0});  // pillar
  add({-0.3, 2.1, 0.0}, {0.9, 2.5, 1.8});       // cabinet against +y wall
  const Eigen::Vector2d crate(2.4, -1.9);
  scene.add_obstacle({2.1, -2.2, 0.0}, {2.7, -1.6, 0.6}, rng, photos, crate);      // crate
  scene.add_obstacle({2.25, -2.05, 0.6}, {2.65, -1.65, 1.0}, rng, photos, crate);  // crate on the crate
  add({-2.85, -0.25, 0.0}, {-2.35, 0.65, 0.5});                                    // low box at -x wall
  // Table: top and four legs.
  const V3 table_min(-2.5, 1.3, 0.0);
  const V3 table_max(-1.3, 2.0, 0.75);
  const Eigen::Vector2d table = 0.5 * (table_min + table_max).head<2>();
  scene.add_obstacle({table_min.x(), table_min.y(), 0.7}, table_max, rng, photos, table);
  for (int i = 0; i < 4; ++i) {
    const double x = (i & 1) ? table_max.x() - 0.1 : table_min.x() + 0.05;
    const double y = (i & 2) ? table_max.y() - 0.1 : table_min.y() + 0.05;
    scene.add_obstacle({x, y, 0.0}, {x + 0.05, y + 0.05, 0.7}, rng, photos, table);
  }
  add({0.3, -2.45, 0.0}, {1.5, -1.9, 0.9});  // sideboard at -y wall
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
  const double s = options_.room_scale();
  Box room = Box::axis_aligned({-3.0 * s, -2.5 * s, 0.0}, {3.0 * s, 2.5 * s, 3.0});
  room.inside = true;
  walk_area_.min_corner = {-3.0 * s, -2.5 * s};
  walk_area_.max_corner = {3.0 * s, 2.5 * s};
  texture_faces(room, rng, photos);
  static_boxes_.push_back(room);
}

void Scene::add_obstacle(const V3& min_corner, const V3& max_corner, Rng& rng,
                         const std::vector<cv::Mat>& photos, const Eigen::Vector2d& anchor) {
  const Eigen::Vector2d shift = (options_.room_scale() - 1.0) * anchor;  // zero in the 6 x 5 m room
  const V3 offset(shift.x(), shift.y(), 0.0);
  Box box = Box::axis_aligned(min_corner + offset, max_corner + offset);
  texture_faces(box, rng, photos);
  static_boxes_.push_back(box);
}

void Scene::add_people(Rng& rng) {
  const CrowdProfile profile = options_.resolved_crowd();
  if (profile == CrowdProfile::kWalk) {
    people_ = simulate_people(options_.people, trajectory_, walk_area_, options_.seed);
  } else {
    Crowd crowd = simulate_crowd(profile, options_.people, trajectory_, walk_area_, options_.seed);
    people_ = std::move(crowd.people);
    blackout_frames_ = {crowd.blackout_first, crowd.blackout_last};
  }
  if (!sprites_.empty()) {
    dress_people_with_sprites();
    return;
  }
  const int width = static_cast<int>(std::ceil(2.0 * (kPersonWidthM + kPersonDepthM) * kTexelsPerMetre));
  const int height = static_cast<int>(std::ceil(kPersonHeightM * kTexelsPerMetre));
  for (size_t i = 0; i < people_.size(); ++i) {
    person_texture_.push_back(static_cast<int>(textures_.size()));
    textures_.emplace_back(make_clothing(width, height, rng));
  }
}

void Scene::add_movers(Rng& rng, const std::vector<cv::Mat>& photos) {
  movers_ = make_movers(options_.movers);
  for (Mover& m : movers_) {
    m.start *= options_.room_scale();  // at the walls of a larger room too
    m.end *= options_.room_scale();
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
  std::vector<Box> boxes =
      sprites_.empty() && !options_.hide_people ? people_boxes(frame) : std::vector<Box>();
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

void Scene::dress_people_with_sprites() {
  Rng rng(options_.seed, 0x5b1e);
  // Sprites grouped by the person they show, the groups in a random order, then taken round robin: the
  // first people all show different persons.
  std::map<std::pair<std::string, int>, std::vector<int>> by_person;
  for (size_t i = 0; i < sprites_.size(); ++i) {
    by_person[{sprites_[i].record.sequence, sprites_[i].record.id}].push_back(static_cast<int>(i));
  }
  std::vector<std::vector<int>> groups;
  for (auto& [key, list] : by_person) groups.push_back(list);
  for (int i = static_cast<int>(groups.size()) - 1; i > 0; --i)
    std::swap(groups[i], groups[rng.below(i + 1)]);
  std::vector<int> order;
  for (size_t round = 0; order.size() < sprites_.size(); ++round) {
    for (const auto& g : groups) {
      if (round < g.size()) order.push_back(g[round]);
    }
  }
  const int frames = frame_count();
  for (size_t i = 0; i < people_.size(); ++i) {
    const int sprite = order[i % order.size()];
    person_sprite_.push_back(sprite);
    const double u = rng.uniform();
    // The group that blacks out the view is tall: its heads reach above the camera's view.
    person_height_m_.push_back(people_[i].role == PersonRole::kBlackout ? 1.8 + 0.1 * u : 1.55 + 0.35 * u);
    // Mirrored while the person walks the other way (across the view) than the photographed one did; the
    // choice changes only when the walk is clearly across the view, so it does not flicker.
    const int facing = sprites_[sprite].record.facing;
    std::vector<std::uint8_t> mirrored(frames, 0);
    bool state = false;
    for (int f = 0; f < frames && facing != 0; ++f) {
      const PersonState& p = people_[i].states[f];
      const Billboard b = facing_billboard(p.position, trajectory_[f].world_from_cam.translation(), 1.0, 1.0);
      const double across = std::cos(p.body_yaw) * b.axis.x() + std::sin(p.body_yaw) * b.axis.y();
      if (f == 0 || std::abs(across) > 0.35) state = across * facing < 0.0;
      mirrored[f] = state ? 1 : 0;
    }
    mirrored_.push_back(std::move(mirrored));
  }
}

std::vector<Billboard> Scene::people_billboards(int frame) const {
  std::vector<Billboard> billboards;
  if (sprites_.empty() || options_.hide_people) return billboards;
  const V3 camera = trajectory_.at(frame).world_from_cam.translation();
  for (size_t i = 0; i < people_.size(); ++i) {
    const Sprite& sprite = sprites_[person_sprite_[i]];
    Billboard b =
        facing_billboard(people_[i].states.at(frame).position, camera, person_height_m_[i], sprite.aspect());
    b.sprite = person_sprite_[i];
    b.mirrored = mirrored_[i][frame] != 0;
    b.person_id = people_[i].id;
    billboards.push_back(b);
  }
  return billboards;
}

geometry::SE3 Scene::right_world_from_cam(int frame) const {
  const geometry::SE3 left_from_right(Eigen::Quaterniond::Identity(), V3(kStereoBaselineM, 0.0, 0.0));
  return trajectory_.at(frame).world_from_cam * left_from_right;
}

}  // namespace crowdslam::synth
