// `crowdslam run --vocabulary`: a missing, truncated or foreign vocabulary file is one error line naming
// the file, exit 1 and no output; a valid one is reported in run.json; `none` runs without one.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <cstdlib>
#include <random>

#include "crowdslam/bow/vocabulary.h"
#include "test_support.h"

using crowdslam::test::run_cli;
using crowdslam::test::TempDir;

namespace {

std::filesystem::path small_sequence(const TempDir& dir) {
  const auto seq = dir / "seq";
  const auto r = run_cli({"-q", "synth", "--out", seq.string(), "--frames", "8", "--width", "320", "--height", "240"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return seq;
}

// A small vocabulary of random descriptors, saved in our binary format.
crowdslam::bow::Vocabulary save_small_vocabulary(const std::filesystem::path& path) {
  std::mt19937 rng(3);
  std::vector<cv::Mat> images;
  for (int i = 0; i < 4; ++i) {
    cv::Mat d(200, 32, CV_8UC1);
    for (int r = 0; r < d.rows; ++r) {
      for (int c = 0; c < 32; ++c) d.at<uint8_t>(r, c) = static_cast<uint8_t>(rng() & 0xFF);
    }
    images.push_back(d);
  }
  crowdslam::bow::VocabularyTrainOptions options;
  options.k = 5;
  options.levels = 2;
  auto vocabulary = crowdslam::bow::Vocabulary::train(images, options);
  vocabulary.save(path.string());
  return vocabulary;
}

void expect_error_naming(const TempDir& dir, const std::filesystem::path& seq, const std::filesystem::path& file,
                         const std::string& what) {
  const auto out = dir / "out";
  const auto r = run_cli({"-q", "run", "--dataset", seq.string(), "--out", out.string(), "--no-people-filter",
                          "--vocabulary", file.string()});
  EXPECT_EQ(r.exit_code, 1) << what;
  EXPECT_NE(r.err.find(file.filename().string()), std::string::npos) << what << ": " << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << what << ": " << r.err;
  EXPECT_FALSE(std::filesystem::exists(out)) << what;
}

}  // namespace

TEST(CliRunVocabulary, MissingTruncatedOrForeignFileIsAnErrorWithoutOutput) {
  TempDir dir;
  const auto seq = small_sequence(dir);
  expect_error_naming(dir, seq, dir / "nope.voc", "missing");

  const auto truncated = dir / "truncated.voc";
  save_small_vocabulary(truncated);
  std::filesystem::resize_file(truncated, std::filesystem::file_size(truncated) / 2);
  expect_error_naming(dir, seq, truncated, "truncated");

  const auto foreign = dir / "foreign.voc";
  crowdslam::test::write_text(foreign, "this is not a vocabulary\n");
  expect_error_naming(dir, seq, foreign, "foreign");
}

TEST(CliRunVocabulary, MissingDefaultVocabularyNamesTheFileAndTheWayOut) {
  TempDir dir;
  const auto seq = small_sequence(dir);
  const auto missing = dir / "default_missing.voc";
  ::setenv("CROWDSLAM_VOCABULARY", missing.string().c_str(), 1);  // the default path (bow/vocabulary_path.h)
  const auto r = run_cli({"-q", "run", "--dataset", seq.string(), "--out", (dir / "out").string(),
                          "--no-people-filter"});
  ::unsetenv("CROWDSLAM_VOCABULARY");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("default_missing.voc"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("--vocabulary none"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "out"));
}

TEST(CliRunVocabulary, LoadedVocabularyIsReportedAndNoneRunsWithout) {
  TempDir dir;
  const auto seq = small_sequence(dir);
  const auto file = dir / "small.voc";
  const auto vocabulary = save_small_vocabulary(file);

  const auto with = run_cli({"-q", "--json", "run", "--dataset", seq.string(), "--out", (dir / "with").string(),
                             "--no-people-filter", "--sequential", "--vocabulary", file.string()});
  ASSERT_EQ(with.exit_code, 0) << with.err;
  const auto doc = nlohmann::json::parse(crowdslam::test::read_text(dir / "with" / "run.json"));
  ASSERT_TRUE(doc["vocabulary"].is_object());
  EXPECT_EQ(doc["vocabulary"]["path"], file.string());
  EXPECT_EQ(doc["vocabulary"]["words"].get<size_t>(), vocabulary.num_words());
  EXPECT_GE(doc["vocabulary"]["load_ms"].get<double>(), 0.0);
  EXPECT_EQ(doc["frames"].size(), 8u);

  const auto without = run_cli({"-q", "run", "--dataset", seq.string(), "--out", (dir / "without").string(),
                                "--no-people-filter", "--sequential", "--vocabulary", "none"});
  ASSERT_EQ(without.exit_code, 0) << without.err;
  const auto doc_none = nlohmann::json::parse(crowdslam::test::read_text(dir / "without" / "run.json"));
  EXPECT_TRUE(doc_none["vocabulary"].is_null());
  EXPECT_EQ(doc_none["frames"].size(), 8u);
}
