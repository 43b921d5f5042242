// util::set_thread_name / lower_thread_priority: one thread's name and nice value change, not the
// process's (read back from /proc/self/task/TID, as `top -H` and perf see them).
#include <gtest/gtest.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <fstream>
#include <string>
#include <thread>

#include "crowdslam/util/thread_priority.h"

using namespace crowdslam;

namespace {
std::string task_comm(long tid) {
  std::ifstream in("/proc/self/task/" + std::to_string(tid) + "/comm");
  std::string name;
  std::getline(in, name);
  return name;
}

long this_tid() { return static_cast<long>(syscall(SYS_gettid)); }
}  // namespace

TEST(ThreadPriority, LowersOnlyTheCallingThread) {
  const int main_before = util::thread_nice();
  int worker_before = -100;
  int worker_after = -100;
  bool ok = false;
  std::thread worker([&] {
    worker_before = util::thread_nice();
    ok = util::lower_thread_priority(3);
    worker_after = util::thread_nice();
  });
  worker.join();
  EXPECT_TRUE(ok);
  EXPECT_EQ(worker_before, main_before);  // a new thread starts at its creator's nice value
  EXPECT_EQ(worker_after, std::min(19, main_before + 3));
  EXPECT_EQ(util::thread_nice(), main_before);  // the process's other threads keep theirs
}

TEST(ThreadPriority, ZeroLeavesThePriorityAndTheNiceValueStopsAt19) {
  int unchanged = -100;
  int clamped = -100;
  std::thread worker([&] {
    const int before = util::thread_nice();
    EXPECT_TRUE(util::lower_thread_priority(0));
    unchanged = util::thread_nice() - before;
    EXPECT_TRUE(util::lower_thread_priority(40));
    clamped = util::thread_nice();
  });
  worker.join();
  EXPECT_EQ(unchanged, 0);
  EXPECT_EQ(clamped, 19);
}

TEST(ThreadPriority, NamesTheCallingThreadKeepingFifteenCharacters) {
  std::string seen;
  std::string seen_long;
  std::thread worker([&] {
    util::set_thread_name("cs-test");
    seen = task_comm(this_tid());
    util::set_thread_name("a-name-longer-than-fifteen");
    seen_long = task_comm(this_tid());
  });
  worker.join();
  EXPECT_EQ(seen, "cs-test");
  EXPECT_EQ(seen_long, "a-name-longer-t");
  EXPECT_NE(task_comm(this_tid()), "cs-test");
}
