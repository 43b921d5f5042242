// Saved maps (issue 12), bad input: every broken or unfitting map file is an InputError naming the file and
// what is wrong, before any frame is processed (no output directory is created); a failed save leaves
// the old file as it was.
#include <gtest/gtest.h>

#include <fstream>

#include "crowdslam/mapdb/map_database.h"
#include "crowdslam/mapdb/schema.h"
#include "crowdslam/util/error.h"
#include "map_test_helpers.h"

using namespace crowdslam;

namespace {

class MapErrors : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    tmp_ = new test::TempDir();
    room_ = test::make_room(*tmp_, 0, 40);
    auto options = test::run_options(room_, *tmp_ / "mapping");
    options.save_map = (*tmp_ / "good.db").string();
    run::run_sequence(options);
  }
  static void TearDownTestSuite() {
    delete tmp_;
    tmp_ = nullptr;
  }

  // A copy of the good map to break.
  std::filesystem::path copy(const std::string& name) const {
    const auto path = *tmp_ / name;
    std::filesystem::copy_file(*tmp_ / "good.db", path, std::filesystem::copy_options::overwrite_existing);
    return path;
  }

  // Runs localisation with `map_file`; expects an InputError containing every one of `parts`, and no output.
  void expect_rejected(const std::filesystem::path& map_file, const std::vector<std::string>& parts,
                       run::RunOptions options = {}) const {
    if (options.dataset.empty()) options = test::run_options(room_, *tmp_ / "never");
    options.load_map = map_file.string();
    options.localization = true;
    try {
      run::run_sequence(options);
      FAIL() << "loading " << map_file << " should fail";
    } catch (const InputError& e) {
      const std::string message = e.what();
      for (const auto& part : parts) EXPECT_NE(message.find(part), std::string::npos) << message;
    }
    EXPECT_FALSE(std::filesystem::exists(options.out_dir)) << "a rejected map must not leave outputs";
  }

  static test::TempDir* tmp_;
  static std::filesystem::path room_;
};

test::TempDir* MapErrors::tmp_ = nullptr;
std::filesystem::path MapErrors::room_;

}  // namespace

TEST_F(MapErrors, MissingFile) { expect_rejected(*tmp_ / "absent.db", {"absent.db", "no such map file"}); }

TEST_F(MapErrors, TruncatedFile) {
  const auto path = copy("truncated.db");
  std::filesystem::resize_file(path, std::filesystem::file_size(path) / 2);
  expect_rejected(path, {"truncated.db"});
}

TEST_F(MapErrors, CorruptFile) {
  const auto path = copy("corrupt.db");
  {
    std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(static_cast<std::streamoff>(std::filesystem::file_size(path) / 2));
    const std::string garbage(4096, '\x5a');
    f.write(garbage.data(), static_cast<std::streamsize>(garbage.size()));
  }
  expect_rejected(path, {"corrupt.db"});
}

TEST_F(MapErrors, NotAMapDatabase) {
  const auto path = *tmp_ / "text.db";
  std::ofstream(path) << "hello, not sqlite\n";
  expect_rejected(path, {"text.db"});
  const auto other = copy("other.db");
  test::exec_sql(other, "DROP TABLE observations");
  expect_rejected(other, {"other.db", "observations missing"});
}

TEST_F(MapErrors, NewerSchema) {
  const auto path = copy("newer.db");
  test::exec_sql(path, "UPDATE schema_version SET version = " + std::to_string(mapdb::kSchemaVersion + 1));
  expect_rejected(path, {"newer.db", "newer than this crowdslam reads"});
}

TEST_F(MapErrors, AnotherSensor) {
  auto options = test::run_options(room_, *tmp_ / "never-mono");
  options.sensor = io::SensorKind::kMonocular;
  expect_rejected(*tmp_ / "good.db", {"good.db", "sensor rgbd in the map, "}, options);
}

TEST_F(MapErrors, AnotherCamera) {
  std::ifstream in(room_ / "settings.yaml");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto at = text.find("Camera.fx: ");
  ASSERT_NE(at, std::string::npos);
  text.replace(at, text.find('\n', at) - at, "Camera.fx: 600.5");
  std::ofstream(*tmp_ / "other_camera.yaml") << text;
  auto options = test::run_options(room_, *tmp_ / "never-camera");
  options.settings_path = (*tmp_ / "other_camera.yaml").string();
  expect_rejected(*tmp_ / "good.db", {"good.db", "camera fx", "600.5 here"}, options);
}

TEST_F(MapErrors, AnotherVocabulary) {
  const auto path = copy("vocabulary.db");
  test::exec_sql(path, "UPDATE metadata SET value = 'fnv1a64:0000000000000001' WHERE key = 'vocabulary.hash'");
  expect_rejected(path, {"vocabulary.db", "vocabulary fnv1a64:0000000000000001"});
}

TEST_F(MapErrors, MapPointObservingAMissingKeyframe) {
  const auto path = copy("dangling.db");
  test::exec_sql(path, "UPDATE observations SET keyframe_id = 999999 WHERE rowid = 1");
  expect_rejected(path, {"dangling.db", "keyframe 999999"});
}

TEST_F(MapErrors, LocalizationNeedsAMapAndSavesNothing) {
  auto options = test::run_options(room_, *tmp_ / "never-options");
  options.localization = true;
  EXPECT_THROW(run::run_sequence(options), InputError);
  options.load_map = (*tmp_ / "good.db").string();
  options.save_map = (*tmp_ / "x.db").string();
  EXPECT_THROW(run::run_sequence(options), InputError);
  EXPECT_FALSE(std::filesystem::exists(options.out_dir));
}

TEST_F(MapErrors, FailedSaveLeavesTheOldFileUntouched) {
  const auto path = copy("keep.db");
  const auto before = test::dump_table(path, "keyframes");
  // The temporary file's name is taken by a directory: the save cannot even start.
  const std::filesystem::path blocker = path.string() + ".tmp." + std::to_string(::getpid());
  std::filesystem::create_directory(blocker);
  std::ofstream(blocker / "inside") << "x";
  auto options = test::run_options(room_, *tmp_ / "failed-save");
  options.save_map = path.string();
  options.overwrite = true;  // an existing map is replaced only with --overwrite (issue 37)
  EXPECT_THROW(run::run_sequence(options), InputError);
  EXPECT_TRUE(test::dump_table(path, "keyframes") == before);
  // The run's outputs say so.
  std::ifstream in(*tmp_ / "failed-save" / "run.json");
  const auto doc = nlohmann::json::parse(in);
  EXPECT_NE(doc["end_state"].get<std::string>().find("failed"), std::string::npos);
  EXPECT_TRUE(doc["map"].contains("save_error"));
}
