#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>

#include "crowdslam/util/atomic_file.h"
#include "crowdslam/util/error.h"
#include "test_support.h"

using namespace crowdslam;

namespace {
std::vector<std::string> temporaries_in(const std::filesystem::path& dir) {
  std::vector<std::string> found;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    if (e.path().filename().string().find(".tmp.") != std::string::npos) found.push_back(e.path().string());
  }
  return found;
}
}  // namespace

TEST(AtomicFile, CommitWritesContent) {
  test::TempDir tmp;
  write_file_atomic(tmp / "out.txt", "hello\n");
  EXPECT_EQ(test::read_text(tmp / "out.txt"), "hello\n");
}

TEST(AtomicFile, AbandonedWriteLeavesNoFileBehind) {
  test::TempDir tmp;
  {
    AtomicFile file(tmp / "out.txt");
    file.stream() << "partial";
    // no commit: simulates an exception thrown mid-write
  }
  EXPECT_FALSE(std::filesystem::exists(tmp / "out.txt"));
  EXPECT_TRUE(std::filesystem::is_empty(tmp.path()));
}

TEST(AtomicFile, AbandonedWriteKeepsOldContent) {
  test::TempDir tmp;
  write_file_atomic(tmp / "out.txt", "old");
  { AtomicFile file(tmp / "out.txt"); file.stream() << "new"; }
  EXPECT_EQ(test::read_text(tmp / "out.txt"), "old");
}

TEST(AtomicFile, MissingDirectoryIsInputError) {
  EXPECT_THROW(AtomicFile("/nonexistent_dir_xyz/out.txt"), InputError);
}

// Issue 37, finding 15: a full disk while rewriting run.json said "write failed" without the reason.
// RLIMIT_FSIZE makes write() fail with EFBIG as a full disk fails with ENOSPC (in a forked child).
TEST(AtomicFile, AFailedWriteSaysWhy) {
  test::TempDir tmp;
  const auto message_file = tmp / "message.txt";
  std::fflush(nullptr);
  const pid_t pid = ::fork();
  if (pid == 0) {
    std::signal(SIGXFSZ, SIG_IGN);
    rlimit limit{4096, 4096};
    ::setrlimit(RLIMIT_FSIZE, &limit);
    std::string message = "no error";
    try {
      write_file_atomic(tmp / "run.json", std::string(200000, 'x'));
    } catch (const InputError& e) {
      message = e.what();
    }
    limit = {RLIM_INFINITY, RLIM_INFINITY};
    ::setrlimit(RLIMIT_FSIZE, &limit);
    test::write_text(message_file, message);
    _exit(0);
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  const std::string message = test::read_text(message_file);
  EXPECT_NE(message.find("run.json: write failed: File too large"), std::string::npos) << message;
  EXPECT_FALSE(std::filesystem::exists(tmp / "run.json"));
  EXPECT_TRUE(temporaries_in(tmp.path()).empty());
}

// Issue 37, finding 15: "<file>.tmp.<pid>" of a process that no longer runs is removed; others are kept.
TEST(AtomicFile, StaleTemporariesOfDeadProcessesAreRemoved) {
  test::TempDir tmp;
  const pid_t child = ::fork();
  if (child == 0) _exit(0);
  ::waitpid(child, nullptr, 0);
  test::write_text(tmp / ("m.db.tmp." + std::to_string(child)), "x");
  test::write_text(tmp / ("m.db.tmp." + std::to_string(::getpid())), "mine");
  test::write_text(tmp / "m.db.tmp.notapid", "x");
  test::write_text(tmp / ("other.db.tmp." + std::to_string(child)), "x");
  EXPECT_EQ(remove_stale_temporaries(tmp / "m.db"), 1u);
  EXPECT_FALSE(std::filesystem::exists(tmp / ("m.db.tmp." + std::to_string(child))));
  EXPECT_TRUE(std::filesystem::exists(tmp / ("m.db.tmp." + std::to_string(::getpid()))));
  EXPECT_TRUE(std::filesystem::exists(tmp / "m.db.tmp.notapid"));
  EXPECT_TRUE(std::filesystem::exists(tmp / ("other.db.tmp." + std::to_string(child))));
}

// Issue 37, finding 15: `synth`'s "<out>.tmp-<pid>" directory of a killed run goes on the next write.
TEST(AtomicFile, StaleTemporaryDirectoriesOfDeadProcessesAreRemoved) {
  test::TempDir tmp;
  const pid_t child = ::fork();
  if (child == 0) _exit(0);
  ::waitpid(child, nullptr, 0);
  const auto dead = tmp / ("seq.tmp-" + std::to_string(child));
  const auto live = tmp / ("seq.tmp-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dead / "rgb");
  test::write_text(dead / "rgb" / "0.png", "x");
  std::filesystem::create_directories(live);
  test::write_text(tmp / ("file.tmp-" + std::to_string(child)), "a file of that naming is not ours");
  std::filesystem::create_symlink(dead, tmp / ("seq2.tmp-" + std::to_string(child)));
  EXPECT_EQ(remove_stale_temporary_dirs(tmp / "file"), 0u);
  EXPECT_EQ(remove_stale_temporary_dirs(tmp / "seq2"), 0u);
  EXPECT_EQ(remove_stale_temporary_dirs(tmp / "seq"), 1u);
  EXPECT_FALSE(std::filesystem::exists(dead));
  EXPECT_TRUE(std::filesystem::exists(live));
  EXPECT_TRUE(std::filesystem::exists(tmp / ("file.tmp-" + std::to_string(child))));
}

// Issue 37, finding 1: an output path naming a device or a FIFO was replaced by the rename.
TEST(AtomicFile, NeverReplacesASpecialFileOrADirectory) {
  test::TempDir tmp;
  const auto fifo = tmp / "fifo";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  // A character device of our own (like /dev/full, when we may create one): never a real /dev node,
  // which a regression would replace.
  std::vector<std::filesystem::path> targets = {fifo, tmp.path()};
  const auto device = tmp / "full";
  if (::mknod(device.c_str(), S_IFCHR | 0600, makedev(1, 7)) == 0) targets.push_back(device);
  for (const auto& path : targets) {
    SCOPED_TRACE(path.string());
    try {
      write_file_atomic(path, "x");
      FAIL() << "replaced " << path;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("not a regular file"), std::string::npos) << e.what();
    }
  }
  EXPECT_TRUE(std::filesystem::is_fifo(fifo));
  if (targets.size() > 2) EXPECT_TRUE(std::filesystem::is_character_file(device));
  EXPECT_TRUE(temporaries_in(tmp.path()).empty());
}
