// `crowdslam run` stopped by a signal (issue 10, finding 1): SIGINT, SIGTERM and SIGHUP stop the run
// cleanly, the trajectory so far and run.json ("interrupted") are written, the exit code is 128 + signal;
// a second signal exits at once. `crowdslam synth` interrupted leaves no temporary directory (finding 14).
#include <gtest/gtest.h>

#include <chrono>
#include <csignal>
#include <filesystem>

#include "run_test_helpers.h"

using namespace crowdslam::test;

namespace {

// Starts a run, waits until its journal holds at least `poses` poses, sends `signal`, waits for the exit.
struct Interrupted {
  CliResult result;
  size_t journal_poses_at_signal = 0;
  double exit_after_signal_s = 0;
};

Interrupted interrupt_run(const std::vector<std::string>& args, const std::filesystem::path& out, size_t poses,
                          int signal, int repeat = 1) {
  CliProcess child(args);
  Interrupted r;
  const bool reached = child.wait_until(
      [&] { return std::filesystem::exists(out / "CameraTrajectory.txt") && trajectory_lines(out / "CameraTrajectory.txt").size() >= poses; },
      300);
  EXPECT_TRUE(reached) << child.current_stderr();
  r.journal_poses_at_signal = trajectory_lines(out / "CameraTrajectory.txt").size();
  const auto sent = std::chrono::steady_clock::now();
  for (int i = 0; i < repeat; ++i) child.send_signal(signal);
  r.result = child.wait(60);
  r.exit_after_signal_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - sent).count();
  return r;
}

void expect_interrupted_outputs(const std::filesystem::path& out, const Interrupted& r, const std::string& signal) {
  const auto doc = read_json(out / "run.json");
  EXPECT_EQ(doc["end_state"], "interrupted");
  const auto lines = trajectory_lines(out / "CameraTrajectory.txt");
  // Every tracked frame is written: the count run.json gives, at least what the journal had at the signal.
  EXPECT_EQ(lines.size(), doc["summary"]["tracked_frames"].get<size_t>());
  EXPECT_GE(lines.size(), r.journal_poses_at_signal);
  for (const auto& line : lines) EXPECT_EQ(count_fields(line), 8u) << line;
  EXPECT_TRUE(std::filesystem::exists(out / "KeyFrameTrajectory.txt"));
  EXPECT_NE(r.result.err.find(signal), std::string::npos) << r.result.err;
  EXPECT_TRUE(temporaries(out).empty());
}

}  // namespace

TEST(CliRunSignals, SigintSigtermSighupWriteTheTrajectorySoFarAndExitWith128PlusSignal) {
  TempDir dir;
  const auto seq = synth_small(dir, 300);
  const std::vector<std::pair<int, std::string>> signals = {{SIGINT, "SIGINT"}, {SIGTERM, "SIGTERM"}, {SIGHUP, "SIGHUP"}};
  for (const auto& [signal, name] : signals) {
    SCOPED_TRACE(name);
    const auto out = dir / ("out_" + name);
    const auto r = interrupt_run({"run", "--dataset", seq.string(), "--out", out.string(), "--no-people-filter"}, out,
                                 30, signal);
    EXPECT_EQ(r.result.exit_code, 128 + signal) << r.result.err;
    expect_interrupted_outputs(out, r, name);
    EXPECT_LT(read_json(out / "run.json")["summary"]["frames"].get<size_t>(), 300u) << "the run went on to the end";
    EXPECT_NE(r.result.out.find("end state         interrupted"), std::string::npos) << r.result.out;
  }
}

TEST(CliRunSignals, InterruptedJsonRunPrintsOneDocumentSayingSo) {
  TempDir dir;
  const auto seq = synth_small(dir, 300);
  const auto out = dir / "out";
  const auto r = interrupt_run({"--json", "run", "--dataset", seq.string(), "--out", out.string(), "--no-people-filter"},
                               out, 30, SIGINT);
  EXPECT_EQ(r.result.exit_code, 130);
  const auto doc = nlohmann::json::parse(r.result.out);  // exactly one document
  EXPECT_EQ(doc["end_state"], "interrupted");
}

TEST(CliRunSignals, SecondSignalExitsAtOnceWithoutTemporaries) {
  TempDir dir;
  const auto seq = synth_small(dir, 300);
  const auto out = dir / "out";
  const auto r = interrupt_run({"run", "--dataset", seq.string(), "--out", out.string(), "--no-people-filter"}, out, 30,
                               SIGINT, 2);
  EXPECT_EQ(r.result.exit_code, 130) << r.result.err;
  EXPECT_TRUE(temporaries(out).empty());
  // Whatever was written is either the interrupted run's end or the journal of a run that was "running".
  const auto doc = read_json(out / "run.json");
  EXPECT_TRUE(doc["end_state"] == "interrupted" || doc["end_state"] == "running") << doc["end_state"];
  for (const auto& line : trajectory_lines(out / "CameraTrajectory.txt")) EXPECT_EQ(count_fields(line), 8u) << line;
}

TEST(CliRunSignals, KilledRunLeavesAValidPartialJournalMarkedRunning) {
  TempDir dir;
  const auto seq = synth_small(dir, 300);
  const auto out = dir / "out";
  const auto r = interrupt_run({"run", "--dataset", seq.string(), "--out", out.string(), "--no-people-filter"}, out, 30,
                               SIGKILL);
  EXPECT_EQ(r.result.exit_code, 128 + SIGKILL);
  EXPECT_EQ(read_json(out / "run.json")["end_state"], "running");  // nothing could say otherwise
  const auto lines = trajectory_lines(out / "CameraTrajectory.txt");
  EXPECT_GE(lines.size(), r.journal_poses_at_signal);
  for (const auto& line : lines) EXPECT_EQ(count_fields(line), 8u) << line;
}

TEST(CliRunSignals, BonnInterruptedAtFrame400KeepsAbout400Poses) {
  CROWDSLAM_REQUIRE_SHARED("bonn_crowd");
  TempDir dir;
  const auto out = dir / "out";
  const auto r = interrupt_run({"run", "--dataset", shared_data("bonn_crowd").string(), "--settings",
                                (source_dir() / "config" / "Bonn.yaml").string(), "--out", out.string()},
                               out, 400, SIGINT);
  EXPECT_EQ(r.result.exit_code, 130) << r.result.err;
  expect_interrupted_outputs(out, r, "SIGINT");
  const auto doc = read_json(out / "run.json");
  const auto frames = doc["summary"]["frames"].get<size_t>();
  EXPECT_GE(frames, 400u);
  EXPECT_LE(frames, 470u);  // stopped within a few frames of the signal (the journal lags by <= 10 poses)
  EXPECT_GE(doc["summary"]["tracked_frames"].get<size_t>(), 395u);
  std::printf("[ measured ] bonn_crowd interrupted: %zu frames, %zu poses, exit %.2f s after SIGINT\n", frames,
              doc["summary"]["tracked_frames"].get<size_t>(), r.exit_after_signal_s);
}

TEST(CliSynthSignals, InterruptedSynthLeavesNoTemporaryDirectory) {
  TempDir dir;
  const auto out = dir / "seq";
  CliProcess child({"synth", "--out", out.string(), "--frames", "3000", "--width", "320", "--height", "240"});
  // Wait until the temporary directory has some frames, then interrupt.
  const bool started = child.wait_until(
      [&] {
        for (const auto& e : std::filesystem::directory_iterator(dir.path())) {
          if (e.path().filename().string().find("seq.tmp-") == 0 && std::filesystem::exists(e.path() / "rgb" / "000005.png")) return true;
        }
        return false;
      },
      120);
  ASSERT_TRUE(started) << child.current_stderr();
  child.send_signal(SIGINT);
  const auto r = child.wait(60);
  EXPECT_EQ(r.exit_code, 130) << r.err;
  EXPECT_NE(r.err.find("interrupted"), std::string::npos) << r.err;
  for (const auto& e : std::filesystem::directory_iterator(dir.path())) ADD_FAILURE() << "left behind: " << e.path();
}

// Issue 37, finding 15: SIGKILL cannot be handled, so its "seq.tmp-<pid>" stays; the next synth to the
// same place removes it (the killed process no longer runs).
TEST(CliSynthSignals, TheNextSynthRemovesTheDirectoryOfAKilledOne) {
  TempDir dir;
  const auto out = dir / "seq";
  CliProcess child({"synth", "--out", out.string(), "--frames", "3000", "--width", "320", "--height", "240"});
  std::filesystem::path left;
  const bool started = child.wait_until(
      [&] {
        for (const auto& e : std::filesystem::directory_iterator(dir.path())) {
          if (e.path().filename().string().find("seq.tmp-") == 0 && std::filesystem::exists(e.path() / "rgb" / "000005.png")) {
            left = e.path();
            return true;
          }
        }
        return false;
      },
      120);
  ASSERT_TRUE(started) << child.current_stderr();
  child.send_signal(SIGKILL);
  child.wait(60);
  ASSERT_TRUE(std::filesystem::exists(left));
  const auto r = run_cli({"synth", "--out", out.string(), "--frames", "3", "--width", "160", "--height", "120"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_FALSE(std::filesystem::exists(left));
  EXPECT_TRUE(std::filesystem::exists(out / "rgb.txt"));
}
