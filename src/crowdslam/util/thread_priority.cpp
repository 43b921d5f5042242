#include "crowdslam/util/thread_priority.h"

#if defined(__linux__)
#include <pthread.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <string>
#endif

namespace crowdslam::util {

#if defined(__linux__)
namespace {
// On Linux, PRIO_PROCESS with a thread id sets that thread alone (setpriority(2), "BUGS").
id_t this_thread_id() { return static_cast<id_t>(syscall(SYS_gettid)); }
}  // namespace

void set_thread_name(const char* name) {
  const std::string truncated = std::string(name).substr(0, 15);
  pthread_setname_np(pthread_self(), truncated.c_str());
}

bool lower_thread_priority(int increment) {
  if (increment <= 0) return true;
  const int target = std::min(19, thread_nice() + increment);
  return setpriority(PRIO_PROCESS, this_thread_id(), target) == 0;
}

int thread_nice() {
  errno = 0;
  const int nice = getpriority(PRIO_PROCESS, this_thread_id());
  return errno == 0 ? nice : 0;
}
#else
void set_thread_name(const char*) {}
bool lower_thread_priority(int) { return true; }
int thread_nice() { return 0; }
#endif

}  // namespace crowdslam::util
