// `crowdslam vocab train`: trains an ORB vocabulary tree from images, videos and datasets.
// `crowdslam vocab info`: size and load time of a vocabulary (our binary format or DBoW2 text).
// `crowdslam vocab convert`: DBoW2 / ORB-SLAM2 text vocabulary (ORBvoc.txt) -> our binary format.
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "commands.h"
#include "crowdslam/bow/vocabulary.h"
#include "crowdslam/bow/vocabulary_path.h"
#include "crowdslam/feature/orb_extractor.h"
#include "crowdslam/io/dataset.h"
#include "crowdslam/io/image_check.h"
#include "crowdslam/io/image_folder_dataset.h"
#include "crowdslam/util/error.h"
#include "crowdslam/util/progress.h"

namespace crowdslam::app {
namespace {
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

struct TrainArgs {
  std::vector<std::string> inputs;
  std::string out;
  bow::VocabularyTrainOptions options;
  int features = 1000;
  std::size_t max_images = 0;
  std::size_t every = 1;
  bool force = false;
};

struct Collected {
  std::vector<cv::Mat> descriptors;  // one per image with descriptors
  std::size_t images = 0;
  std::size_t rows = 0;
};

bool is_image_file(const std::string& input) {
  std::error_code ec;
  return fs::is_regular_file(input, ec) && io::is_image_file_name(input);
}

// Images the inputs will give (every --every-th frame of each, at most --max-images); 0: unknown (an input
// that does not know its frame count).
std::size_t expected_images(const TrainArgs& args) {
  std::size_t images = 0;
  for (const std::string& input : args.inputs) {
    const std::size_t frames = is_image_file(input) ? 1 : io::open_source(input)->summary().frames.value_or(0);
    if (frames == 0) return args.max_images;
    images += is_image_file(input) ? 1 : (frames + args.every - 1) / args.every;
  }
  return args.max_images > 0 ? std::min(images, args.max_images) : images;
}

// Collects ORB descriptors image by image, input by input, until `max_images` are in.
class DescriptorCollector {
 public:
  DescriptorCollector(const TrainArgs& args, ProgressLine& progress) : args_(args), progress_(progress) {
    feature::ORBExtractor::Options orb;  // the defaults of config/TUM1.yaml: 1000, 1.2, 8, 20/7
    orb.num_features = args.features;
    orb.check();
    extractor_ = std::make_unique<feature::ORBExtractor>(orb);
  }

  bool full() const { return args_.max_images > 0 && result_.images >= args_.max_images; }

  void add(const cv::Mat& image) {
    std::vector<cv::KeyPoint> keypoints;
    cv::Mat descriptors;
    extractor_->extract(feature::to_gray(image), keypoints, descriptors);
    ++result_.images;
    if (descriptors.rows > 0) {
      result_.rows += static_cast<std::size_t>(descriptors.rows);
      result_.descriptors.push_back(descriptors);
    }
    progress_.update(result_.images, std::to_string(result_.rows) + " descriptors");
  }

  // Every image of one input (an image file, a folder, a dataset or a video).
  void add_input(const std::string& input) {
    const std::size_t images_before = result_.images;
    const std::size_t rows_before = result_.rows;
    if (is_image_file(input)) {
      if (!full()) add(io::read_colour_image(input));
    } else {
      const auto source = io::open_source(input);
      std::size_t index = 0;
      while (!full()) {
        const auto frame = source->next();
        if (!frame) break;
        if (index++ % args_.every == 0) add(frame->images.colour);
      }
    }
    const std::size_t images = result_.images - images_before;
    const std::size_t rows = result_.rows - rows_before;
    if (images > 0 && rows == 0) {
      progress_.end_line();
      spdlog::warn("{}: no ORB features in {} image(s)", input, images);
    }
    spdlog::debug("read {}: {} images, {} descriptors", input, images, rows);
  }

  Collected take() { return std::move(result_); }

 private:
  const TrainArgs& args_;
  ProgressLine& progress_;
  std::unique_ptr<feature::ORBExtractor> extractor_;
  Collected result_;
};

std::string join(const std::vector<std::string>& items) {
  std::string out;
  for (const auto& item : items) out += (out.empty() ? "" : ", ") + item;
  return out;
}

void check_train_args(const TrainArgs& args) {
  const bow::VocabularyTrainOptions& o = args.options;
  if (o.k < 2) throw InputError("--k must be at least 2, got " + std::to_string(o.k));
  if (o.levels < 1 || o.levels > 255)
    throw InputError("--levels must be in [1, 255], got " + std::to_string(o.levels));
  o.check();
  if (args.features < 1)
    throw InputError("--features must be at least 1, got " + std::to_string(args.features));
  if (args.every < 1) throw InputError("--every must be at least 1");
  std::error_code ec;
  if (fs::exists(args.out, ec) && !args.force)
    throw input_error(args.out, "output exists (use --force to replace it)");
  if (fs::is_directory(args.out, ec)) throw input_error(args.out, "output is a directory");
  // Every input must exist before any work starts (a bare number would open a camera otherwise).
  for (const std::string& input : args.inputs) {
    if (!fs::exists(input, ec)) throw input_error(input, "no such file or directory");
  }
}

void run_train(TrainArgs& args, const GlobalOptions& global) {
  check_train_args(args);
  const bool show_progress = !global.quiet;
  const auto start = Clock::now();
  ProgressLine read_progress(show_progress, expected_images(args), "image");
  DescriptorCollector collector(args, read_progress);
  for (const std::string& input : args.inputs) {
    if (collector.full()) break;
    collector.add_input(input);
  }
  read_progress.finish();
  const Collected data = collector.take();
  const double read_s = seconds_since(start);
  if (data.rows == 0) {
    throw input_error(join(args.inputs), "no ORB descriptors in " + std::to_string(data.images) +
                                             " image(s): nothing to train a vocabulary on");
  }
  spdlog::info("read {} images, {} descriptors in {:.1f} s", data.images, data.rows, read_s);

  // One progress line per tree level (descriptors clustered at that level).
  std::unique_ptr<ProgressLine> level_progress;
  int last_level = 0;
  args.options.progress = [&](const bow::VocabularyTrainProgress& p) {
    if (p.level != last_level) {
      level_progress = std::make_unique<ProgressLine>(show_progress, p.descriptors_total, "descriptor");
      last_level = p.level;
    }
    level_progress->update(p.descriptors_done, fmt::format("k-means level {}/{}", p.level, p.levels));
    if (p.descriptors_done == p.descriptors_total) {
      level_progress.reset();  // its last line
      spdlog::info("k-means: level {}/{} done after {:.1f} s", p.level, p.levels, seconds_since(start) - read_s);
    }
  };
  const auto train_start = Clock::now();
  const bow::Vocabulary voc = bow::Vocabulary::train(data.descriptors, args.options);
  const double train_s = seconds_since(train_start);
  voc.save(args.out);  // atomic: a failure leaves no file
  if (global.json) {
    print_json({{"out", args.out},
                {"inputs", args.inputs},
                {"images", data.images},
                {"descriptors", data.rows},
                {"k", voc.k()},
                {"levels", voc.levels()},
                {"depth", voc.depth()},
                {"nodes", voc.num_nodes()},
                {"words", voc.num_words()},
                {"seed", args.options.seed},
                {"read_s", read_s},
                {"train_s", train_s}});
    return;
  }
  std::printf("images       %zu\n", data.images);
  std::printf("descriptors  %zu\n", data.rows);
  std::printf("tree         k %d, L %d, depth %d, %zu nodes, %zu words\n", voc.k(), voc.levels(), voc.depth(),
              voc.num_nodes(), voc.num_words());
  std::printf("time_s       read %.1f, train %.1f\n", read_s, train_s);
  std::printf("written      %s\n", args.out.c_str());
  std::fflush(stdout);
}

void run_info(const std::string& path, const GlobalOptions& global) {
  const auto start = Clock::now();
  const bow::Vocabulary voc = bow::Vocabulary::read(path);
  const double load_ms = 1e3 * seconds_since(start);
  std::error_code ec;
  const auto bytes = fs::file_size(path, ec);
  if (global.json) {
    print_json({{"path", path},
                {"bytes", ec ? 0 : bytes},
                {"k", voc.k()},
                {"levels", voc.levels()},
                {"depth", voc.depth()},
                {"nodes", voc.num_nodes()},
                {"words", voc.num_words()},
                {"load_ms", load_ms}});
    return;
  }
  std::printf("file     %s (%.1f MB)\n", path.c_str(), ec ? 0.0 : static_cast<double>(bytes) / 1e6);
  std::printf("k        %d\n", voc.k());
  std::printf("L        %d\n", voc.levels());
  std::printf("depth    %d\n", voc.depth());
  std::printf("nodes    %zu\n", voc.num_nodes());
  std::printf("words    %zu\n", voc.num_words());
  std::printf("load_ms  %.1f\n", load_ms);
  std::fflush(stdout);
}

void run_convert(const std::string& in, const std::string& out, bool force, const GlobalOptions& global) {
  std::error_code ec;
  if (fs::exists(out, ec) && !force) throw input_error(out, "output exists (use --force to replace it)");
  const auto start = Clock::now();
  const bow::Vocabulary voc = bow::Vocabulary::read(in);
  voc.save(out);
  const double seconds = seconds_since(start);
  if (global.json) {
    print_json({{"in", in},
                {"out", out},
                {"nodes", voc.num_nodes()},
                {"words", voc.num_words()},
                {"seconds", seconds}});
    return;
  }
  std::printf("converted %s -> %s (%zu nodes, %zu words, %.1f s)\n", in.c_str(), out.c_str(), voc.num_nodes(),
              voc.num_words(), seconds);
  std::fflush(stdout);
}

}  // namespace

void add_vocab_command(CLI::App& app, const GlobalOptions& global) {
  CLI::App* vocab = app.add_subcommand("vocab", "ORB vocabulary tree: train, info, convert");
  vocab->require_subcommand(1);

  auto train_args = std::make_shared<TrainArgs>();
  train_args->options.levels = 5;
  CLI::App* train = vocab->add_subcommand(
      "train", "Train a vocabulary from image files, image folders, videos and datasets (our ORB)");
  train->add_option("--out", train_args->out, "Output vocabulary (binary, written atomically)")->required();
  train->add_option("--k", train_args->options.k, "Branching factor")->capture_default_str();
  train->add_option("--levels", train_args->options.levels, "Depth L of the tree")->capture_default_str();
  train->add_option("--seed", train_args->options.seed, "k-means++ seed (same inputs and seed: same bytes)")
      ->capture_default_str();
  train->add_option("--features", train_args->features, "ORB features per image")->capture_default_str();
  train->add_option("--max-images", train_args->max_images, "Stop reading after this many images (0 = all)")
      ->capture_default_str();
  train->add_option("--every", train_args->every, "Use every Nth frame of videos, folders and datasets")
      ->capture_default_str();
  train->add_flag("--force", train_args->force, "Replace an existing output file");
  train->add_option("inputs", train_args->inputs, "Image files, image folders, videos, datasets")->required();
  train->callback([train_args, &global] { run_train(*train_args, global); });

  auto info_path = std::make_shared<std::string>();
  CLI::App* info = vocab->add_subcommand("info", "k, L, depth, nodes, words and load time of a vocabulary");
  info->add_option("file", *info_path, "Vocabulary (binary or DBoW2 text; default: the default vocabulary)");
  info->callback([info_path, &global] {
    run_info(info_path->empty() ? bow::default_vocabulary_path() : *info_path, global);
  });

  struct ConvertArgs {
    std::string in;
    std::string out;
    bool force = false;
  };
  auto convert_args = std::make_shared<ConvertArgs>();
  CLI::App* convert =
      vocab->add_subcommand("convert", "DBoW2 / ORB-SLAM2 text vocabulary (ORBvoc.txt) -> our binary format");
  convert->add_option("in", convert_args->in, "Input vocabulary (DBoW2 text or binary)")->required();
  convert->add_option("out", convert_args->out, "Output binary vocabulary (written atomically)")->required();
  convert->add_flag("--force", convert_args->force, "Replace an existing output file");
  convert->callback([convert_args, &global] {
    run_convert(convert_args->in, convert_args->out, convert_args->force, global);
  });
}

}  // namespace crowdslam::app
