// `crowdslam synth-sprites`: cuts person sprites out of MOT sequences (grabCut inside the ground-truth
// boxes) for the billboard people of `crowdslam synth`.
#include <spdlog/spdlog.h>

#include <memory>

#include "commands.h"
#include "crowdslam/synth/sprites.h"
#include "crowdslam/util/error.h"
#include "crowdslam/util/interrupt.h"

namespace crowdslam::app {

void add_synth_sprites_command(CLI::App& app, const GlobalOptions& global) {
  struct Args {
    std::string out;
    std::vector<std::string> mot;
    bool force = false;
    synth::SpriteExtractOptions options;
  };
  auto args = std::make_shared<Args>();
  CLI::App* cmd = app.add_subcommand(
      "synth-sprites",
      "Cut person sprites out of MOT sequences (grabCut in the ground-truth boxes) for `synth`");
  cmd->add_option("--out", args->out, "Output directory (written atomically), e.g. <repo>/people_sprites")
      ->required();
  cmd->add_option(
      "--mot", args->mot,
      "MOT sequence folders (img1/, gt/gt.txt) or folders of them (default: $CROWDSLAM_SHARED/data/mot, "
      "else ../shared/data/mot)");
  cmd->add_option("--min-height", args->options.min_height_px, "Smallest ground-truth box height in pixels")
      ->capture_default_str();
  cmd->add_option("--max-overlap", args->options.max_overlap,
                  "Largest fraction of a box another box may cover")
      ->capture_default_str();
  cmd->add_option("--per-id", args->options.per_id, "Sprites per person (from frames at least 10 apart)")
      ->capture_default_str();
  cmd->add_option("--max-sprites", args->options.max_sprites, "Most sprites in all")->capture_default_str();
  cmd->add_option("--iterations", args->options.iterations, "grabCut iterations")->capture_default_str();
  cmd->add_flag("--force", args->force, "Replace an existing non-empty output directory");
  cmd->callback([args, &global] {
    args->options.check();
    std::vector<std::filesystem::path> sequences;
    std::vector<std::string> roots = args->mot;
    if (roots.empty()) roots.push_back(synth::default_mot_dir().string());
    for (const std::string& root : roots) {
      const auto found = synth::find_mot_sequences(root);
      if (found.empty()) throw input_error(root, "no MOT sequences here (folders with img1/ and gt/gt.txt)");
      sequences.insert(sequences.end(), found.begin(), found.end());
    }
    InterruptScope interrupts;  // a signal removes the unfinished output
    const synth::SpriteSet set = synth::extract_sprites(
        sequences, args->out, args->options, args->force, [&global](const synth::SequenceSprites& s) {
          if (!global.json) {
            spdlog::info("synth-sprites: {}: {} boxes, {} candidates, {} sprites, {} masks rejected", s.name,
                         s.boxes, s.candidates, s.sprites, s.rejected);
          }
        });
    if (global.json) {
      nlohmann::json j{
          {"out", args->out}, {"count", set.sprites.size()}, {"sequences", nlohmann::json::array()}};
      for (const auto& s : set.sequences) {
        j["sequences"].push_back({{"name", s.name},
                                  {"boxes", s.boxes},
                                  {"candidates", s.candidates},
                                  {"sprites", s.sprites},
                                  {"rejected", s.rejected}});
      }
      print_json(j);
      return;
    }
    spdlog::info("synth-sprites: wrote {} sprites and sprites.json to {}", set.sprites.size(), args->out);
  });
}

}  // namespace crowdslam::app
