#include <gtest/gtest.h>

#include "crowdslam/util/atomic_file.h"
#include "crowdslam/util/error.h"
#include "test_support.h"

using namespace crowdslam;

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
