#pragma once
// SIGINT / SIGTERM / SIGHUP handling, and temporary files that never outlive the process.
//
// Two ways a command reacts to a signal:
//   - cooperative (InterruptScope, used by `run` and `synth`): the first signal only records itself;
//     the command polls interrupted() between frames, stops its threads, writes what it has and exits
//     with 128 + signal. A second signal removes the registered temporary files and exits at once.
//   - immediate (install_cleanup_handlers(), every other command): the signal removes the registered
//     temporary files, then the process dies of the signal as it would have without a handler.
// The signal handlers only use async-signal-safe calls (write, unlink, _exit, signal, raise).
//
// TempFileRegistry: AtomicFile registers its "<path>.tmp.<pid>" here while it is open, so a signal
// never leaves one behind (SIGKILL still can: the next `run --overwrite` removes stale ones).
#include <exception>
#include <string>

namespace crowdslam {

// Installs the immediate handlers for SIGINT, SIGTERM and SIGHUP (idempotent).
void install_cleanup_handlers();

// Cooperative handling while alive; the immediate handlers again afterwards.
class InterruptScope {
 public:
  InterruptScope();
  ~InterruptScope();
  InterruptScope(const InterruptScope&) = delete;
  InterruptScope& operator=(const InterruptScope&) = delete;
};

// While alive (inside an InterruptScope: a command writing its final outputs, e.g. run.json and the
// saved map), a second signal does not exit at once, which would leave run.json saying "running": it
// only says the outputs are being written, and a third signal exits at once.
class FinishingScope {
 public:
  FinishingScope();
  ~FinishingScope();
  FinishingScope(const FinishingScope&) = delete;
  FinishingScope& operator=(const FinishingScope&) = delete;
};

// The first signal received inside an InterruptScope (SIGINT, SIGTERM, SIGHUP), or 0.
int interrupt_signal();
inline bool interrupted() { return interrupt_signal() != 0; }
// "SIGINT", "SIGTERM", "SIGHUP", or "signal N".
std::string signal_name(int signal);
// Forgets a recorded signal (tests that run several scopes in one process).
void clear_interrupt();

// Thrown by code that polls interrupted() and gives up its work; main turns it into 128 + signal.
class Interrupted : public std::exception {
 public:
  explicit Interrupted(int signal);
  [[nodiscard]] const char* what() const noexcept override { return message_.c_str(); }
  [[nodiscard]] int signal() const { return signal_; }
  [[nodiscard]] int exit_code() const { return 128 + signal_; }

 private:
  int signal_;
  std::string message_;
};

// Throws Interrupted when a signal was received.
void throw_if_interrupted();

// Paths unlinked by the signal handlers. Fixed capacity (64); register() returns -1 when full (the file
// is then only removed by its owner).
namespace temp_files {
int add(const std::string& path);
void remove(int slot);
}  // namespace temp_files

}  // namespace crowdslam
