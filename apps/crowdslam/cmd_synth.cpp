// `crowdslam synth`: renders a synthetic room sequence (RGB-D or stereo, optionally with walking people)
// with ground-truth poses and people boxes.
#include <spdlog/spdlog.h>

#include <cmath>
#include <memory>

#include "commands.h"
#include "crowdslam/synth/sprites.h"
#include "crowdslam/synth/writer.h"
#include "crowdslam/util/interrupt.h"
#include "crowdslam/util/progress.h"

namespace crowdslam::app {

void add_synth_command(CLI::App& app, GlobalOptions& global) {
  struct Args {
    std::string out;
    std::string trajectory = "loop";
    std::string crowd = "auto";
    std::string sprites;
    synth::SynthOptions options;
  };
  auto args = std::make_shared<Args>();
  CLI::App* cmd = app.add_subcommand(
      "synth", "Render a synthetic room sequence (TUM RGB-D or KITTI stereo layout) with ground truth");
  cmd->add_option("--out", args->out, "Output directory (written atomically)")->required();
  cmd->add_option("--frames", args->options.frames, "Number of frames (30 fps)")->capture_default_str();
  cmd->add_option("--seed", args->options.seed, "Random seed (textures, people, shake)")->capture_default_str();
  cmd->add_option("--people", args->options.people, "Number of walking people")->capture_default_str();
  cmd->add_option("--movers", args->options.movers,
                  "Moving objects that are not people (0-4: sliding crate, door, cart, door); writes mask/ "
                  "with the moving pixels of each frame")
      ->capture_default_str();
  cmd->add_flag("--stereo", args->options.stereo, "Rectified stereo pair, KITTI layout, instead of RGB-D");
  cmd->add_flag("--hide-people", args->options.hide_people,
                "Render the same sequence (room, camera, the people's paths) without the people: the empty-room "
                "baseline of a crowd");
  cmd->add_option("--trajectory", args->trajectory, "Camera path: loop, line, sweep or handheld")
      ->capture_default_str();
  cmd->add_option("--width", args->options.width, "Image width in pixels")->capture_default_str();
  cmd->add_option("--height", args->options.height, "Image height in pixels")->capture_default_str();
  cmd->add_option("--noise-depth", args->options.noise_depth_m, "Sigma of Gaussian depth noise in metres")
      ->capture_default_str();
  cmd->add_option("--textures", args->options.texture_dir, "Directory of photographs used as textures")
      ->capture_default_str();
  cmd->add_option("--crowd", args->crowd,
                  "How the people behave: auto (passing with sprites, walk with box people), walk, passing, "
                  "standing, near or blackout")
      ->capture_default_str();
  cmd->add_option(
      "--sprites", args->sprites,
      "Person sprites (crowdslam synth-sprites) for billboard people; default <repo>/people_sprites "
      "when built; 'none' for textured box people");
  cmd->add_flag("--force", args->options.force, "Replace an existing non-empty output directory");
  cmd->callback([args, &global] {
    args->options.trajectory = synth::parse_trajectory_kind(args->trajectory);
    args->options.crowd = synth::parse_crowd_profile(args->crowd);
    const synth::SpriteChoice sprites = synth::resolve_sprite_dir(args->sprites);
    args->options.sprite_dir = sprites.dir;
    if (args->options.people > 0 && !sprites.notice.empty()) spdlog::warn("{}", sprites.notice);
    InterruptScope interrupts;  // a signal stops the rendering and removes the unfinished output
    ProgressLine progress(!global.quiet, static_cast<size_t>(args->options.frames), "frame");
    const synth::SequenceSummary s =
        synth::write_sequence(args->options, args->out, [&progress](int done, int) {
          progress.update(static_cast<size_t>(done), "");
        });
    progress.finish();
    if (global.json) {
      nlohmann::json j{{"out", args->out},
                       {"frames", s.frames},
                       {"person_boxes", s.person_boxes},
                       {"max_person_coverage", s.max_person_coverage},
                       {"textures", s.photo_textures ? "photos" : "procedural"},
                       {"people_model", s.sprite_people ? "sprites" : "boxes"},
                       {"crowd", s.crowd},
                       {"seconds", s.seconds}};
      if (std::isfinite(s.min_person_distance_m)) j["min_person_distance_m"] = s.min_person_distance_m;
      print_json(j);
      return;
    }
    spdlog::info(
        "synth: wrote {} frames to {} in {:.1f} s ({} person boxes, textures: {}, people: {}, crowd: {})",
        s.frames, args->out, s.seconds, s.person_boxes, s.photo_textures ? "photos" : "procedural",
        s.sprite_people ? "sprites" : "boxes", s.crowd);
    if (std::isfinite(s.min_person_distance_m)) {
      spdlog::info("synth: closest person to the camera {:.2f} m, largest image coverage {:.0f}%",
                   s.min_person_distance_m, 100.0 * s.max_person_coverage);
    }
  });
}

}  // namespace crowdslam::app
