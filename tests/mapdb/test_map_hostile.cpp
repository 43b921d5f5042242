// Saved maps against hostile edits and hostile save targets (issue 37, findings 1, 3, 4, 12, 13, 15):
// next ids not above the stored ids, non-finite or mistyped numbers, counts that wrap around, corrupt
// metadata are "corrupt map" errors naming the file, for every reader; a map is only ever written over
// nothing or (with --overwrite) over a crowdslam map, never over a device, a FIFO or another file; a
// save removes the temporaries a killed save left; a signal after the last frame still ends the run
// "interrupted" with its outputs complete.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <fstream>

#include "crowdslam/mapdb/map_database.h"
#include "crowdslam/mapdb/map_export.h"
#include "crowdslam/mapdb/map_target.h"
#include "crowdslam/util/error.h"
#include "crowdslam/util/interrupt.h"
#include "map_test_helpers.h"

using namespace crowdslam;

namespace {

class MapHostile : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    tmp_ = new test::TempDir();
    room_ = test::make_room(*tmp_, 0, 30);
    auto options = test::run_options(room_, *tmp_ / "mapping");
    options.save_map = (*tmp_ / "good.db").string();
    run::run_sequence(options);
  }
  static void TearDownTestSuite() {
    delete tmp_;
    tmp_ = nullptr;
  }

  static std::filesystem::path copy(const std::string& name) {
    const auto path = *tmp_ / name;
    std::filesystem::copy_file(*tmp_ / "good.db", path, std::filesystem::copy_options::overwrite_existing);
    return path;
  }

  // Every reader refuses the file with a message naming it and containing each of `parts`.
  static void expect_corrupt(const std::filesystem::path& path, const std::vector<std::string>& parts) {
    const auto check = [&](const std::string& message, const char* reader) {
      EXPECT_FALSE(message.empty()) << reader << " accepted " << path;
      EXPECT_EQ(message.rfind(path.string(), 0), 0u) << reader << ": " << message;
      EXPECT_EQ(message.find('\n'), std::string::npos) << reader << ": " << message;
      for (const auto& part : parts) EXPECT_NE(message.find(part), std::string::npos) << reader << ": " << message;
    };
    check(test::error_of([&] { mapdb::read_map_info(path); }), "map info");
    check(test::error_of([&] { mapdb::read_map_contents(path); }), "view");
    const auto ply = path.string() + ".ply";
    check(test::error_of([&] { mapdb::export_points_ply(path, ply); }), "export");
    EXPECT_FALSE(std::filesystem::exists(ply));
    auto options = test::run_options(room_, *tmp_ / ("never_" + path.filename().string()));
    options.load_map = path.string();
    check(test::error_of([&] { run::run_sequence(options); }), "run --load-map");
    EXPECT_FALSE(std::filesystem::exists(options.out_dir));
  }

  static test::TempDir* tmp_;
  static std::filesystem::path room_;
};

test::TempDir* MapHostile::tmp_ = nullptr;
std::filesystem::path MapHostile::room_;

}  // namespace

// Finding 3: new keyframes and points would take the ids of loaded ones.
TEST_F(MapHostile, NextIdsNotAboveTheStoredIdsAreCorrupt) {
  // 0, -1, and the largest stored id itself (the next keyframe would take it).
  int n = 0;
  for (const std::string value : {"'0'", "'-1'", "(SELECT CAST(MAX(id) AS TEXT) FROM keyframes)"}) {
    SCOPED_TRACE(value);
    const auto path = copy("next_ids" + std::to_string(n++) + ".db");
    test::exec_sql(path, "UPDATE metadata SET value = " + value + " WHERE key = 'map.next_keyframe_id'");
    expect_corrupt(path, {"corrupt map", "map.next_keyframe_id"});
  }
  const auto points = copy("next_point_id.db");
  test::exec_sql(points, "UPDATE metadata SET value = '0' WHERE key = 'map.next_map_point_id'");
  expect_corrupt(points, {"corrupt map", "map.next_map_point_id"});
}

// Finding 12: text where a number belongs, and numbers out of every sane range.
TEST_F(MapHostile, CorruptMetadataNumbersAreCorruptMapErrors) {
  const std::vector<std::pair<std::string, std::string>> edits = {
      {"map.next_keyframe_id", "abc"}, {"map.next_map_point_id", "1e3"}, {"camera.fx", "inf"},
      {"camera.width", "1e300"},       {"orb.levels", "1000000000"},      {"vocabulary.words", "-5"}};
  for (const auto& [key, value] : edits) {
    SCOPED_TRACE(key + " = " + value);
    const auto path = copy("meta_" + key + ".db");
    test::exec_sql(path, "UPDATE metadata SET value = '" + value + "' WHERE key = '" + key + "'");
    expect_corrupt(path, {"corrupt map", key});
  }
}

// Finding 12: a count that wraps around when multiplied by the record size.
TEST_F(MapHostile, KeypointCountThatWrapsAroundIsCorrupt) {
  const auto path = copy("wrap.db");
  test::exec_sql(path,
                 "UPDATE keyframes SET num_keypoints = 4611686018427387904, keypoints = x'', descriptors = x'' "
                 "WHERE id = (SELECT MIN(id) FROM keyframes)");
  expect_corrupt(path, {"corrupt map", "keyframe", "num_keypoints"});
}

// Finding 4: SQLite stores 9e999 as infinity; text in a REAL column reads back as 0.
TEST_F(MapHostile, NonFiniteOrMistypedNumbersAreCorrupt) {
  const std::vector<std::pair<std::string, std::vector<std::string>>> edits = {
      {"UPDATE keyframes SET tx = 9e999 WHERE id = (SELECT MIN(id) FROM keyframes)", {"keyframe", "tx"}},
      {"UPDATE keyframes SET timestamp = -9e999 WHERE id = (SELECT MAX(id) FROM keyframes)", {"keyframe", "timestamp"}},
      {"UPDATE map_points SET x = 9e999 WHERE id = (SELECT MIN(id) FROM map_points)", {"map point", " x "}},
      {"UPDATE map_points SET nz = 'abc' WHERE id = (SELECT MIN(id) FROM map_points)", {"map point", "nz"}},
      {"UPDATE observations SET keypoint_index = -3 WHERE rowid = 1", {"observation", "keypoint_index"}},
  };
  int i = 0;
  for (const auto& [sql, parts] : edits) {
    SCOPED_TRACE(sql);
    const auto path = copy("nonfinite" + std::to_string(i++) + ".db");
    test::exec_sql(path, sql);
    auto expected = parts;
    expected.push_back("corrupt map");
    expect_corrupt(path, expected);
  }
}

// Finding 1: what --save-map / map optimise --out may replace.
TEST_F(MapHostile, MapTargetsAreOnlyNewFilesOrMapsWithOverwrite) {
  const auto dir = *tmp_ / "targets";
  std::filesystem::create_directories(dir);
  const auto fifo = dir / "fifo";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  // A character device like /dev/full (1, 7) when we may create one (root), else the FIFO again.
  const auto device = dir / "full";
  const bool have_device = ::mknod(device.c_str(), S_IFCHR | 0600, makedev(1, 7)) == 0;
  const auto yaml = dir / "important.yaml";
  test::write_text(yaml, "%YAML:1.0\nCamera.fx: 500\n");
  const auto map = copy("targets/existing.db");

  EXPECT_NO_THROW(mapdb::check_map_target(dir / "new.db", false, "--save-map"));
  EXPECT_NO_THROW(mapdb::check_map_target(map, true, "--save-map"));
  const std::vector<std::pair<std::filesystem::path, std::string>> refused = {
      {fifo, "not a regular file"},     {yaml, "not a crowdslam map"}, {map, "--overwrite"},
      {dir, "not a regular file"},      {"", "empty path"},            {dir / "missing" / "x.db", "does not exist"}};
  for (const auto& [path, part] : refused) {
    SCOPED_TRACE(path.string());
    const std::string message = test::error_of([&, p = path] { mapdb::check_map_target(p, false, "--save-map"); });
    EXPECT_NE(message.find(part), std::string::npos) << message;
    EXPECT_NE(message.find("--save-map"), std::string::npos) << message;
  }
  if (have_device) {
    EXPECT_NE(test::error_of([&] { mapdb::check_map_target(device, true, "--save-map"); }).find("not a regular file"),
              std::string::npos);
  }
  // Even --overwrite never replaces anything but a map.
  EXPECT_FALSE(test::error_of([&] { mapdb::check_map_target(yaml, true, "--out"); }).empty());
  EXPECT_FALSE(test::error_of([&] { mapdb::check_map_target(fifo, true, "--out"); }).empty());

  // A run refuses before it starts: no output directory, the FIFO and the YAML untouched.
  for (const auto& target : {fifo, yaml}) {
    auto options = test::run_options(room_, dir / "never");
    options.save_map = target.string();
    options.overwrite = true;
    EXPECT_THROW(run::run_sequence(options), InputError);
    EXPECT_FALSE(std::filesystem::exists(dir / "never"));
  }
  EXPECT_TRUE(std::filesystem::is_fifo(fifo));
  EXPECT_EQ(test::read_text(yaml), "%YAML:1.0\nCamera.fx: 500\n");
  // save_map itself never renames over a special file (one put there after the checks).
  map::Map empty;
  EXPECT_THROW(mapdb::save_map(fifo, empty, mapdb::read_map_header(map)), InputError);
  EXPECT_TRUE(std::filesystem::is_fifo(fifo));
  // Finding 13: an empty path is an error, not "no map".
  auto options = test::run_options(room_, dir / "never_empty");
  options.save_map_given = true;
  EXPECT_NE(test::error_of([&] { run::run_sequence(options); }).find("empty path"), std::string::npos);
}

// Finding 15: a save killed with SIGKILL leaves "FILE.db.tmp.PID"; the next save removes it (and only
// temporaries of processes that no longer run).
TEST_F(MapHostile, NextSaveRemovesStaleTemporaries) {
  const auto dir = *tmp_ / "stale";
  std::filesystem::create_directories(dir);
  const pid_t child = ::fork();
  if (child == 0) _exit(0);
  ASSERT_GT(child, 0);
  ::waitpid(child, nullptr, 0);  // its pid now names no process
  const auto stale = dir / ("m.db.tmp." + std::to_string(child));
  const auto live = dir / ("m.db.tmp." + std::to_string(::getppid()));  // a process that runs
  const auto other = dir / ("other.db.tmp." + std::to_string(child));  // not this map's
  for (const auto& p : {stale, live, other}) test::write_text(p, "half a map");
  auto options = test::run_options(room_, dir / "out");
  options.save_map = (dir / "m.db").string();
  run::run_sequence(options);
  EXPECT_FALSE(std::filesystem::exists(stale));
  EXPECT_TRUE(std::filesystem::exists(live));
  EXPECT_TRUE(std::filesystem::exists(other));
  EXPECT_NO_THROW(mapdb::read_map_info(dir / "m.db"));
}

namespace {
// Sends SIGINT to the process from on_finish (after the last frame, while the run stops its threads):
// `count` times.
class SignalAtFinish : public system::RunObserver {
 public:
  explicit SignalAtFinish(int count) : count_(count) {}
  void on_finish(const system::EndState& /*end*/) override {
    for (int i = 0; i < count_; ++i) std::raise(SIGINT);
  }

 private:
  int count_;
};
}  // namespace

// Finding 15: a signal after the last frame ended the run "completed" (exit 0); a second one exited at
// once, leaving run.json "running" and no KeyFrameTrajectory.txt. Now: "interrupted", every output
// written, the map saved.
TEST_F(MapHostile, SignalsDuringTheFinalSaveEndTheRunInterruptedWithItsOutputs) {
  for (int signals : {1, 2}) {
    SCOPED_TRACE(signals);
    const auto out = *tmp_ / ("late_signal" + std::to_string(signals));
    auto options = test::run_options(room_, out);
    options.save_map = (out.string() + ".db");
    SignalAtFinish observer(signals);
    options.observers.push_back(&observer);
    run::RunSummary summary;
    {
      InterruptScope scope;
      summary = run::run_sequence(options);
    }
    clear_interrupt();
    EXPECT_EQ(summary.end.kind, system::EndState::Kind::kInterrupted);
    EXPECT_EQ(summary.end.signal, SIGINT);
    std::ifstream in(out / "run.json");
    EXPECT_EQ(nlohmann::json::parse(in)["end_state"], "interrupted");
    EXPECT_TRUE(std::filesystem::exists(out / "KeyFrameTrajectory.txt"));
    EXPECT_NO_THROW(mapdb::read_map_info(options.save_map));
  }
}
