// Hostile but fair use of the command line (issue 37): map files and exports never replace what is not
// theirs (findings 1, 13), a corrupt map is one line naming it (14), special files and huge inputs are
// refused at once (6, 7), every error is exit 1 with one JSON document under --json (9), unclear
// messages say what is wrong (17), a missing first image is skipped and time going backwards is warned
// about (16).
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>

#include <chrono>
#include <fstream>

#include "run_test_helpers.h"

using namespace crowdslam::test;

namespace {

// "1305031102.175304 rgb/1305031102.175304.png" -> "rgb/1305031102.175304.png"
std::string split_first_image(const std::string& line) { return line.substr(line.find(' ') + 1); }

size_t count_lines(const std::string& text) {
  size_t n = 0;
  for (char c : text) n += c == '\n';
  return n;
}

// One line on stderr, "error: ...", naming every part.
void expect_one_line_error(const CliResult& r, const std::vector<std::string>& parts) {
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_EQ(count_lines(r.err), 1u) << r.err;
  EXPECT_EQ(r.err.rfind("error: ", 0), 0u) << r.err;
  for (const auto& part : parts) EXPECT_NE(r.err.find(part), std::string::npos) << r.err;
}

class CliHostile : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir();
    seq_ = synth_small(*dir_, 40, "seq", {"--people", "2"});
    const auto r = run_cli({"-q", "run", "--dataset", seq_.string(), "--out", (*dir_ / "base_run").string(),
                            "--no-people-filter", "--save-map", (*dir_ / "base.db").string()});
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }
  static std::vector<std::string> run_args(const std::filesystem::path& out) {
    return {"run", "--dataset", seq_.string(), "--out", out.string(), "--no-people-filter", "--vocabulary", "none",
            "--frames", "5"};
  }
  static TempDir* dir_;
  static std::filesystem::path seq_;
};

TempDir* CliHostile::dir_ = nullptr;
std::filesystem::path CliHostile::seq_;

}  // namespace

// Finding 1: --save-map and map optimise --out replace only a crowdslam map, and only with --overwrite.
TEST_F(CliHostile, SaveMapNeverReplacesADeviceAFifoOrAnotherFile) {
  TempDir tmp;
  const auto fifo = tmp / "fifo";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  std::vector<std::filesystem::path> targets = {fifo, seq_ / "rgb.txt", seq_ / "settings.yaml"};
  const auto device = tmp / "full";
  if (::mknod(device.c_str(), S_IFCHR | 0600, makedev(1, 7)) == 0) targets.push_back(device);  // as root
  for (const auto& target : targets) {
    SCOPED_TRACE(target.string());
    const auto before = std::filesystem::is_regular_file(target) ? read_text(target) : std::string();
    auto args = run_args(tmp / "never");
    args.insert(args.end(), {"--save-map", target.string(), "--overwrite"});
    expect_one_line_error(run_cli(args), {target.string()});
    EXPECT_FALSE(std::filesystem::exists(tmp / "never"));
    if (std::filesystem::is_regular_file(target)) EXPECT_EQ(read_text(target), before);
    // map optimise --out with --overwrite: the same rule.
    expect_one_line_error(
        run_cli({"map", "optimise", (*dir_ / "base.db").string(), "--out", target.string(), "--overwrite"}),
        {target.string()});
  }
  EXPECT_TRUE(std::filesystem::is_fifo(fifo));
  // An existing map: only with --overwrite.
  const auto map = tmp / "copy.db";
  std::filesystem::copy_file(*dir_ / "base.db", map);
  auto args = run_args(tmp / "no_overwrite");
  args.insert(args.end(), {"--save-map", map.string()});
  expect_one_line_error(run_cli(args), {map.string(), "--overwrite"});
  args.push_back("--overwrite");
  EXPECT_EQ(run_cli(args).exit_code, 0);
  // Finding 13: an empty path.
  auto empty = run_args(tmp / "empty");
  empty.insert(empty.end(), {"--save-map", ""});
  expect_one_line_error(run_cli(empty), {"--save-map"});
  EXPECT_FALSE(std::filesystem::exists(tmp / "empty"));
}

// Finding 1: an export never overwrites the map it reads, another map, or another export of the call.
TEST_F(CliHostile, MapExportNeverOverwritesTheMapOrItsOtherOutputs) {
  TempDir tmp;
  const auto map = tmp / "v.db";
  std::filesystem::copy_file(*dir_ / "base.db", map);
  const auto info_before = run_cli({"--json", "map", "info", map.string()});
  ASSERT_EQ(info_before.exit_code, 0);
  expect_one_line_error(run_cli({"map", "export", map.string(), "--ply", map.string()}), {map.string()});
  expect_one_line_error(
      run_cli({"map", "export", map.string(), "--ply", (tmp / "a.ply").string(), "--keyframes", (tmp / "a.ply").string()}),
      {"a.ply", "--keyframes"});
  const auto other_map = tmp / "other.db";
  std::filesystem::copy_file(*dir_ / "base.db", other_map);
  expect_one_line_error(run_cli({"map", "export", map.string(), "--trajectory", other_map.string()}),
                        {other_map.string(), "crowdslam map"});
  EXPECT_FALSE(std::filesystem::exists(tmp / "a.ply"));
  EXPECT_EQ(run_cli({"--json", "map", "info", map.string()}).out, info_before.out);
  EXPECT_EQ(run_cli({"map", "export", map.string(), "--ply", (tmp / "ok.ply").string()}).exit_code, 0);
}

// Finding 14: SQLite's report of a damaged file spans lines; the error is one line naming the file.
TEST_F(CliHostile, DamagedMapIsOneLineNamingTheFile) {
  TempDir tmp;
  const auto map = tmp / "damaged.db";
  std::filesystem::copy_file(*dir_ / "base.db", map);
  auto bytes = read_bytes(map);
  ASSERT_GT(bytes.size(), 5 * 4096u);
  for (size_t i = 2 * 4096 + 8; i < 4 * 4096; ++i) bytes[i] = static_cast<unsigned char>(i * 131);
  write_bytes(map, bytes);
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{"map", "info", map.string()}, {"map", "export", map.string(), "--ply", (tmp / "x.ply").string()}}) {
    const auto r = run_cli(args);
    expect_one_line_error(r, {map.string()});
  }
}

// Finding 9: every error, parse errors included, is exit 1 with exactly one JSON document on stdout.
TEST_F(CliHostile, EveryErrorIsExitOneWithOneJsonDocument) {
  TempDir tmp;
  const std::vector<std::vector<std::string>> cases = {
      {"--json", "run", "--dataset", seq_.string(), "--out", (tmp / "a").string(), "--viewer-port", "70000"},
      {"--json", "run", "--dataset", seq_.string(), "--out", (tmp / "b").string(), "--no-such-option"},
      {"--json", "run", "--dataset", seq_.string(), "--out", (tmp / "c").string(), "--frames", "-1"},
      {"--json", "run", "--dataset", seq_.string(), "--out", (tmp / "d").string(), "--save-frames", "-2"},
      {"--json", "no-such-command"},
      {"--json"},
      {"run", "--json", "--dataset", seq_.string()},
  };
  for (const auto& args : cases) {
    std::string joined;
    for (const auto& a : args) joined += a + " ";
    SCOPED_TRACE(joined);
    const auto r = run_cli(args);
    EXPECT_EQ(r.exit_code, 1) << r.err;
    EXPECT_EQ(count_lines(r.err), 1u) << r.err;
    nlohmann::json doc;
    ASSERT_NO_THROW(doc = nlohmann::json::parse(r.out)) << r.out;
    EXPECT_EQ(doc["exit_code"], 1);
    EXPECT_TRUE(doc["error"].is_string());
  }
  for (const char* name : {"a", "b", "c", "d"}) EXPECT_FALSE(std::filesystem::exists(tmp / name));
}

// Findings 6 and 17: a device, FIFO or directory is refused at once with a message saying what it is.
TEST_F(CliHostile, SpecialFilesAndDirectoriesAreRefusedAtOnce) {
  TempDir tmp;
  const auto gt = seq_ / "groundtruth.txt";
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"run", "--dataset", seq_.string(), "--out", (tmp / "a").string(), "--detections", "/dev/zero"}, "not a regular file"},
      {{"run", "--dataset", seq_.string(), "--out", (tmp / "b").string(), "--detections", tmp.path().string()}, "is a directory"},
      {{"run", "--dataset", seq_.string(), "--out", (tmp / "c").string(), "--vocabulary", tmp.path().string()}, "is a directory"},
      {{"run", "--dataset", seq_.string(), "--out", (tmp / "d").string(), "--vocabulary", "/dev/zero"}, "not a regular file"},
      {{"eval", "ate", "/dev/zero", gt.string()}, "not a regular file"},
      {{"eval", "ate", tmp.path().string(), gt.string()}, "is a directory"},
      {{"vocab", "info", "/dev/zero"}, "not a regular file"},
      {{"map", "info", "/dev/zero"}, "not a regular file"},
  };
  for (const auto& [args, part] : cases) {
    SCOPED_TRACE(args[args.size() - 1]);
    const auto start = std::chrono::steady_clock::now();
    const auto r = run_cli(args);
    expect_one_line_error(r, {part});
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 20.0);
  }
  for (const char* name : {"a", "b", "c", "d"}) EXPECT_FALSE(std::filesystem::exists(tmp / name));
  // A line without an end (a huge binary file) is refused by its length, not read into memory.
  const auto blob = tmp / "blob.txt";
  {
    std::ofstream out(blob, std::ios::binary);
    const std::string zeros(1 << 20, '\0');
    for (int i = 0; i < 9; ++i) out << zeros;
  }
  expect_one_line_error(run_cli({"eval", "ate", blob.string(), gt.string()}), {"blob.txt:1", "longer than"});
}

// Finding 7: tens of thousands of boxes in one frame keep the 2000 most confident, with a warning that
// counts the rest (was 20 s a frame and more).
TEST_F(CliHostile, ThirtyThousandBoxesInOneFrameKeepTheMostConfident) {
  TempDir tmp;
  const auto boxes = tmp / "boxes.txt";
  {
    std::ofstream out(boxes);
    // 28,000 weak boxes all over frame 1, then 2,000 strong ones in the top-left corner; frame 2 has one.
    for (int i = 0; i < 28000; ++i) out << "1,-1," << 100 + (i % 200) << "," << 100 + (i % 100) << ",20,40,0.6\n";
    for (int i = 0; i < 2000; ++i) out << "1,-1," << (i % 30) << "," << (i % 20) << ",20,40,0.9\n";
    out << "2,-1,10,10,20,40,0.9\n";
  }
  const auto out = tmp / "out";
  const std::vector<std::string> args = {"run", "--dataset", seq_.string(), "--out", out.string(), "--detections", boxes.string(),
          "--vocabulary", "none", "--frames", "3", "--sequential"};
  const auto r = run_cli(args);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("1 frame with more than 2000 person boxes (first: frame 1)"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("skipped 28000 boxes"), std::string::npos) << r.err;
  EXPECT_EQ(read_json(out / "run.json")["end_state"], "completed");
}

// Finding 17: a flag setting given a word says what it expects.
TEST_F(CliHostile, FlagSettingGivenAWordSaysZeroOrOne) {
  TempDir tmp;
  const auto settings = tmp / "settings.yaml";
  write_text(settings, read_text(seq_ / "settings.yaml") + "Detector.tracker: \"bogus\"\n");
  auto args = run_args(tmp / "out");
  args.insert(args.end(), {"--settings", settings.string()});
  expect_one_line_error(run_cli(args), {"Detector.tracker", "expected 0 or 1", "bogus"});
}

// Finding 16: with --skip-bad-frames a missing first image is skipped like any other; timestamps that go
// backwards are warned about.
TEST_F(CliHostile, MissingFirstImageIsSkippedAndBackwardTimeIsWarned) {
  TempDir tmp;
  const auto seq = tmp / "seq";
  std::filesystem::copy(seq_, seq, std::filesystem::copy_options::recursive);
  const auto lines = trajectory_lines(seq / "rgb.txt");
  ASSERT_GE(lines.size(), 10u);
  const auto first_image = seq / split_first_image(lines[0]);
  ASSERT_TRUE(std::filesystem::remove(first_image)) << first_image;
  auto r = run_cli({"--json", "run", "--dataset", seq.string(), "--out", (tmp / "skip").string(), "--no-people-filter",
                    "--vocabulary", "none", "--frames", "8", "--skip-bad-frames", "--allow-untracked"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_GE(nlohmann::json::parse(r.out)["input"]["skipped_frames"].get<int>(), 1);
  // rgb.txt in reverse order.
  std::string reversed = "# reversed\n";
  for (auto it = lines.rbegin(); it != lines.rend(); ++it) reversed += *it + "\n";
  write_text(seq / "rgb.txt", reversed);
  r = run_cli({"run", "--dataset", seq.string(), "--out", (tmp / "reversed").string(), "--no-people-filter",
               "--vocabulary", "none", "--frames", "4", "--allow-untracked"});
  EXPECT_NE(r.err.find("rgb.txt:3: time stamp"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("not in time order"), std::string::npos) << r.err;
}
