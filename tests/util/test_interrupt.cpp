// Signals: inside an InterruptScope the first SIGINT/SIGTERM/SIGHUP is only recorded (the command stops
// at its next check); outside, a signal removes the registered temporary files (AtomicFile) and kills
// the process as before. Checked in forked children, so the test process keeps its own handlers.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <filesystem>

#include "crowdslam/util/atomic_file.h"
#include "crowdslam/util/interrupt.h"
#include "test_support.h"

using crowdslam::test::TempDir;
namespace fs = std::filesystem;

namespace {
// Runs `child` in a forked process; returns its wait status.
template <typename F>
int in_child(F&& child) {
  std::fflush(nullptr);
  const pid_t pid = ::fork();
  if (pid == 0) {
    child();
    _exit(0);
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  return status;
}
}  // namespace

TEST(Interrupt, FirstSignalInsideAScopeIsRecordedNotFatal) {
  for (int signal : {SIGINT, SIGTERM, SIGHUP}) {
    const int status = in_child([signal] {
      crowdslam::InterruptScope scope;
      if (crowdslam::interrupted()) _exit(3);
      std::raise(signal);
      if (crowdslam::interrupt_signal() != signal) _exit(4);
      try {
        crowdslam::throw_if_interrupted();
        _exit(5);
      } catch (const crowdslam::Interrupted& e) {
        if (e.exit_code() != 128 + signal) _exit(6);
      }
      _exit(0);
    });
    ASSERT_TRUE(WIFEXITED(status)) << "killed by signal " << WTERMSIG(status);
    EXPECT_EQ(WEXITSTATUS(status), 0) << crowdslam::signal_name(signal);
  }
}

TEST(Interrupt, SecondSignalExitsAtOnceWith128PlusSignal) {
  const int status = in_child([] {
    crowdslam::InterruptScope scope;
    std::raise(SIGTERM);
    std::raise(SIGTERM);
    _exit(0);  // not reached
  });
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 128 + SIGTERM);
}

TEST(Interrupt, SignalOutsideAScopeRemovesOpenTemporaryFilesAndKills) {
  TempDir dir;
  const auto target = dir / "result.txt";
  const int status = in_child([&] {
    crowdslam::install_cleanup_handlers();
    crowdslam::AtomicFile file(target);
    file.stream() << "half of it";
    file.stream().flush();
    std::raise(SIGINT);
    _exit(0);  // not reached
  });
  ASSERT_TRUE(WIFSIGNALED(status));
  EXPECT_EQ(WTERMSIG(status), SIGINT);
  EXPECT_TRUE(fs::is_empty(dir.path())) << "temporary left behind";
}

TEST(Interrupt, CommittedFilesAreNotRemoved) {
  TempDir dir;
  const auto target = dir / "result.txt";
  const int status = in_child([&] {
    crowdslam::install_cleanup_handlers();
    crowdslam::write_file_atomic(target, "complete\n");
    std::raise(SIGTERM);
  });
  ASSERT_TRUE(WIFSIGNALED(status));
  EXPECT_EQ(crowdslam::test::read_text(target), "complete\n");
}

// Issue 37, finding 15: a second Ctrl-C while the outputs are written left run.json "running"; while a
// FinishingScope lives, the second signal only says so, and a third exits at once.
TEST(Interrupt, WhileFinishingASecondSignalIsNotFatalAndAThirdIs) {
  const int survived = in_child([] {
    crowdslam::InterruptScope scope;
    std::raise(SIGINT);
    crowdslam::FinishingScope finishing;
    std::raise(SIGINT);
    if (crowdslam::interrupt_signal() != SIGINT) _exit(3);
    _exit(0);
  });
  ASSERT_TRUE(WIFEXITED(survived)) << "killed by signal " << WTERMSIG(survived);
  EXPECT_EQ(WEXITSTATUS(survived), 0);
  const int third = in_child([] {
    crowdslam::InterruptScope scope;
    crowdslam::FinishingScope finishing;
    std::raise(SIGINT);
    std::raise(SIGINT);
    std::raise(SIGINT);
    _exit(0);  // not reached
  });
  ASSERT_TRUE(WIFEXITED(third));
  EXPECT_EQ(WEXITSTATUS(third), 128 + SIGINT);
}
