// `crowdslam vocab train / info / convert` end to end on images, a video and a DBoW2 text file made here.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>
#include <string>
#include <vector>

#include "crowdslam/bow/vocabulary.h"
#include "crowdslam/feature/orb_extractor.h"
#include "test_support.h"

namespace {
namespace fs = std::filesystem;
using crowdslam::bow::Vocabulary;
using crowdslam::test::read_text;
using crowdslam::test::run_cli;
using crowdslam::test::TempDir;
using crowdslam::test::write_text;

// A blocky random texture (corners at the block junctions), slightly blurred: plenty of ORB features.
cv::Mat textured_image(unsigned seed, cv::Size size = {320, 240}) {
  cv::Mat blocks(size.height / 8, size.width / 8, CV_8UC1);
  cv::RNG rng(seed);
  rng.fill(blocks, cv::RNG::UNIFORM, 0, 256);
  cv::Mat image;
  cv::resize(blocks, image, size, 0, 0, cv::INTER_NEAREST);
  cv::GaussianBlur(image, image, {3, 3}, 0.8);
  cv::Mat colour;
  cv::cvtColor(image, colour, cv::COLOR_GRAY2BGR);
  return colour;
}

// ORB descriptor count of an image file with our extractor and a budget (what `vocab train` must see).
int descriptors_of(const fs::path& path, int features) {
  crowdslam::feature::ORBExtractor extractor;
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  extractor.extract(cv::imread(path.string(), cv::IMREAD_GRAYSCALE), features, keypoints, descriptors);
  return descriptors.rows;
}

// Folder `images/` with `n` textured PNGs plus a single JPEG `single.jpg` beside it.
struct TrainingImages {
  fs::path folder;
  fs::path single;
  int descriptors = 0;  // with a budget of 300
};

TrainingImages make_images(const TempDir& tmp, int n) {
  TrainingImages t{tmp / "images", tmp / "single.jpg", 0};
  fs::create_directories(t.folder);
  for (int i = 0; i < n; ++i) {
    const fs::path path = t.folder / ("img" + std::to_string(i) + ".png");
    cv::imwrite(path.string(), textured_image(10 + i));
    t.descriptors += descriptors_of(path, 300);
  }
  cv::imwrite(t.single.string(), textured_image(99, {400, 300}));
  t.descriptors += descriptors_of(t.single, 300);
  return t;
}

int entries_in(const fs::path& dir) {
  int n = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir)) ++n;
  return n;
}

TEST(CliVocab, TrainsALoadableVocabularyOfTheRequestedShape) {
  TempDir tmp;
  const TrainingImages images = make_images(tmp, 4);
  ASSERT_GT(images.descriptors, 1000);
  const fs::path out = tmp / "voc.bin";
  const auto r = run_cli({"--json", "vocab", "train", "--out", out.string(), "--k", "4", "--levels", "3",
                          "--features", "300", images.folder.string(), images.single.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto summary = nlohmann::json::parse(r.out);
  EXPECT_EQ(summary["images"], 5);
  EXPECT_EQ(summary["descriptors"], images.descriptors);  // every image once, with the --features budget

  const Vocabulary voc = Vocabulary::load(out.string());
  EXPECT_EQ(voc.k(), 4);
  EXPECT_EQ(voc.levels(), 3);
  EXPECT_EQ(voc.depth(), 3);
  EXPECT_LE(voc.num_words(), 64u);  // 4^3
  EXPECT_GE(voc.num_words(), 40u);  // > 1000 distinct descriptors fill most of the tree
  EXPECT_EQ(summary["nodes"], voc.num_nodes());
  EXPECT_EQ(summary["words"], voc.num_words());
  // IDF over 5 images: every weight is in [0, log 5].
  for (crowdslam::bow::WordId w = 0; w < voc.num_words(); ++w) {
    EXPECT_GE(voc.word_weight(w), 0.0f);
    EXPECT_LE(voc.word_weight(w), std::log(5.0f) + 1e-6f);
  }
  EXPECT_EQ(entries_in(tmp.path()), 3);  // images/, single.jpg, voc.bin: no temporaries

  // An existing output needs --force.
  const auto again = run_cli({"vocab", "train", "--out", out.string(), images.single.string()});
  EXPECT_EQ(again.exit_code, 1);
  EXPECT_NE(again.err.find(out.string()), std::string::npos) << again.err;
  EXPECT_NE(again.err.find("--force"), std::string::npos) << again.err;
}

TEST(CliVocab, SameInputsAndSeedGiveIdenticalBytes) {
  TempDir tmp;
  const TrainingImages images = make_images(tmp, 3);
  auto train = [&](const std::string& name, const std::string& seed) {
    const auto r = run_cli({"vocab", "train", "--out", (tmp / name).string(), "--k", "5", "--levels", "3",
                            "--seed", seed, "--features", "300", images.folder.string()});
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return read_text(tmp / name);
  };
  const std::string a = train("a.voc", "7");
  const std::string b = train("b.voc", "7");
  const std::string c = train("c.voc", "8");
  ASSERT_GT(a.size(), 32u);
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);  // the seed matters
}

TEST(CliVocab, VideoFramesEveryNthAndMaxImages) {
  TempDir tmp;
  const fs::path video = tmp / "clip.avi";
  {
    cv::VideoWriter writer(video.string(), cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 10.0,
                           cv::Size(320, 240));
    ASSERT_TRUE(writer.isOpened());
    for (int i = 0; i < 7; ++i) writer.write(textured_image(200 + i));
  }
  auto images_used = [&](std::vector<std::string> extra) {
    std::vector<std::string> args = {
        "--json", "vocab", "train",    "--force", "--out",      (tmp / "v.voc").string(),
        "--k",    "3",     "--levels", "2",       "--features", "200"};
    args.insert(args.end(), extra.begin(), extra.end());
    const auto r = run_cli(args);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return r.exit_code == 0 ? nlohmann::json::parse(r.out)["images"].get<int>() : -1;
  };
  EXPECT_EQ(images_used({video.string()}), 7);
  EXPECT_EQ(images_used({"--every", "3", video.string()}), 3);  // frames 0, 3, 6
  EXPECT_EQ(images_used({"--max-images", "2", video.string()}), 2);
}

// Runs a training that must fail: exit 1, the message names `named`, and no output file.
void expect_refused(const TempDir& tmp, const std::vector<std::string>& inputs, const std::string& named,
                    const std::string& reason) {
  const fs::path out = tmp / "never.voc";
  std::vector<std::string> args = {"vocab", "train", "--out", out.string()};
  args.insert(args.end(), inputs.begin(), inputs.end());
  const auto r = run_cli(args);
  EXPECT_EQ(r.exit_code, 1) << named;
  EXPECT_NE(r.err.find(named), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(reason), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));
}

TEST(CliVocab, BadInputsAreRefusedNamingThePath) {
  TempDir tmp;
  const fs::path good = tmp / "good.png";
  cv::imwrite(good.string(), textured_image(5));
  const fs::path missing = tmp / "missing_folder";
  expect_refused(tmp, {good.string(), missing.string()}, missing.string(), "no such file");

  const fs::path text = tmp / "notes.txt";
  write_text(text, "these are not pixels\n");
  expect_refused(tmp, {good.string(), text.string()}, text.string(), "video");

  const fs::path broken = tmp / "broken.png";
  write_text(broken, "\x89PNG\r\n\x1a\n not really");
  expect_refused(tmp, {broken.string()}, broken.string(), "");

  const fs::path empty = tmp / "empty";
  fs::create_directories(empty);
  expect_refused(tmp, {empty.string()}, empty.string(), "");

  const fs::path blank = tmp / "blank.png";  // uniform grey: no corners, no descriptors
  cv::imwrite(blank.string(), cv::Mat(240, 320, CV_8UC1, cv::Scalar(128)));
  expect_refused(tmp, {blank.string()}, blank.string(), "no ORB descriptors");

  // Only the inputs made above are left: no partial or temporary output.
  EXPECT_EQ(entries_in(tmp.path()), 5);
}

// "b b ... b" (32 bytes) with byte `at` replaced by `other`.
std::string bytes(int b, int at = -1, int other = 0) {
  std::string out;
  for (int i = 0; i < 32; ++i) out += std::to_string(i == at ? other : b) + (i < 31 ? " " : "");
  return out;
}

// DBoW2 text tree, k = 2, L = 2: inner nodes 1 (zeros) and 2 (0xFF), leaves 3..6 with weights 0.1..0.4.
std::string small_dbow2_text() {
  return "2 2 0 0\n0 0 " + bytes(0) + " 0\n0 0 " + bytes(255) + " 0\n1 1 " + bytes(0, 0, 15) + " 0.1\n1 1 " +
         bytes(0, 31, 240) + " 0.2\n2 1 " + bytes(255, 0, 0) + " 0.3\n2 1 " + bytes(255, 31, 0) + " 0.4\n";
}

TEST(CliVocab, ConvertsDbow2TextToBinaryAndInfoReportsBoth) {
  TempDir tmp;
  write_text(tmp / "voc.txt", small_dbow2_text());
  const fs::path out = tmp / "voc.bin";
  const auto r = run_cli({"vocab", "convert", (tmp / "voc.txt").string(), out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Vocabulary voc = Vocabulary::load(out.string());  // our binary format now
  EXPECT_EQ(voc.k(), 2);
  EXPECT_EQ(voc.levels(), 2);
  ASSERT_EQ(voc.num_nodes(), 7u);
  ASSERT_EQ(voc.num_words(), 4u);
  for (crowdslam::bow::WordId w = 0; w < 4; ++w) {
    EXPECT_EQ(voc.word_node(w), w + 3);
    EXPECT_FLOAT_EQ(voc.word_weight(w), 0.1f * static_cast<float>(w + 1));
  }
  EXPECT_EQ(voc.node_descriptor(4)[31], 240);
  EXPECT_EQ(voc.parent(5), 2u);

  for (const fs::path& file : {tmp / "voc.txt", out}) {
    const auto info = run_cli({"--json", "vocab", "info", file.string()});
    ASSERT_EQ(info.exit_code, 0) << info.err;
    const auto j = nlohmann::json::parse(info.out);
    EXPECT_EQ(j["k"], 2);
    EXPECT_EQ(j["levels"], 2);
    EXPECT_EQ(j["depth"], 2);
    EXPECT_EQ(j["nodes"], 7);
    EXPECT_EQ(j["words"], 4);
    EXPECT_GE(j["load_ms"].get<double>(), 0.0);
  }
  EXPECT_EQ(fs::file_size(out), 32u + 7u * 44u);  // header + 44 bytes per node
  // Plain-text info lists the same numbers.
  const auto text = run_cli({"vocab", "info", out.string()});
  EXPECT_NE(text.out.find("words    4\n"), std::string::npos) << text.out;
  EXPECT_NE(text.out.find("nodes    7\n"), std::string::npos) << text.out;

  // No overwrite without --force; a malformed text file names the file and line.
  EXPECT_EQ(run_cli({"vocab", "convert", (tmp / "voc.txt").string(), out.string()}).exit_code, 1);
  write_text(tmp / "bad.txt", "2 2 0 0\n0 0 1 2 3\n");
  const auto bad = run_cli({"vocab", "convert", (tmp / "bad.txt").string(), (tmp / "bad.bin").string()});
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.err.find((tmp / "bad.txt").string() + ":2"), std::string::npos) << bad.err;
  EXPECT_FALSE(fs::exists(tmp / "bad.bin"));
  // info of a missing file names it.
  const auto missing = run_cli({"vocab", "info", (tmp / "nope.voc").string()});
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_NE(missing.err.find("nope.voc"), std::string::npos) << missing.err;
}

}  // namespace
