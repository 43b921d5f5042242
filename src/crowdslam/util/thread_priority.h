#pragma once
// Names and scheduling priority of the system's own threads (Linux; elsewhere both do nothing).
//
// Tracking is the run's critical path: every frame waits for it, and for the reader and the person
// detector that feed it. Local mapping, loop closing and the global bundle adjustment take what CPU
// they are given, and a busy mapper only makes keyframes less often. SystemOptions::background_nice
// (`crowdslam run --background-nice`) can therefore run them with a lower priority (a higher nice
// value), so on a machine with fewer cores than busy threads the kernel gives the frame's path the core
// first (docs/PROFILE.md, "Thread priorities").

namespace crowdslam::util {

// Names the calling thread (at most 15 characters are kept) for `top -H`, `perf report --sort comm`
// and debuggers.
void set_thread_name(const char* name);

// Raises the calling thread's nice value by `increment` (0 leaves it; clamped to the system's 19).
// Only this thread changes, not the process. Returns false if the system refused.
bool lower_thread_priority(int increment);

// The calling thread's nice value (0 for a process started normally).
int thread_nice();

}  // namespace crowdslam::util
