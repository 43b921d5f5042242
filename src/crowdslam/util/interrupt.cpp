#include "crowdslam/util/interrupt.h"

#include <unistd.h>

#include <array>
#include <atomic>
#include <csignal>
#include <cstring>

namespace crowdslam {

namespace {

constexpr int kSlots = 64;
constexpr size_t kMaxPath = 4096;

// A slot is 0 (free), 1 (being written or cleared) or 2 (holds a path the handlers may unlink).
struct Slot {
  std::atomic<int> state{0};
  char path[kMaxPath] = {};
};
std::array<Slot, kSlots> g_slots;

std::atomic<int> g_signal{0};
std::atomic<bool> g_cooperative{false};
std::atomic<bool> g_finishing{false};
std::atomic<int> g_extra_signals{0};  // signals after the first, while finishing

void unlink_registered() {
  for (auto& slot : g_slots) {
    if (slot.state.load() == 2) ::unlink(slot.path);
  }
}

void write_stderr(const char* text) {
  const ssize_t ignored = ::write(STDERR_FILENO, text, std::strlen(text));
  (void)ignored;
}

const char* name_of(int signal) {
  switch (signal) {
    case SIGINT:
      return "SIGINT";
    case SIGTERM:
      return "SIGTERM";
    case SIGHUP:
      return "SIGHUP";
    default:
      return "signal";
  }
}

extern "C" void on_signal(int signal) {
  if (g_cooperative.load()) {
    int expected = 0;
    if (g_signal.compare_exchange_strong(expected, signal)) {
      write_stderr("\ninterrupted (");
      write_stderr(name_of(signal));
      write_stderr(g_finishing.load() ? "): writing the outputs; send it twice more to exit at once\n"
                                      : "): stopping and writing the outputs; send it again to exit at once\n");
      return;
    }
    if (g_finishing.load() && g_extra_signals.fetch_add(1) == 0) {
      write_stderr("\nstill writing the outputs (run.json, the map); send it once more to exit at once, "
                   "leaving them incomplete\n");
      return;
    }
    // Second signal (third while finishing): leave at once.
    unlink_registered();
    _exit(128 + signal);
  }
  unlink_registered();
  std::signal(signal, SIG_DFL);
  std::raise(signal);
}

void install(bool cooperative) {
  g_cooperative.store(cooperative);
  struct sigaction action {};
  action.sa_handler = on_signal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESTART;  // reads in other threads (image decoding) must not fail with EINTR
  for (int signal : {SIGINT, SIGTERM, SIGHUP}) sigaction(signal, &action, nullptr);
}

}  // namespace

void install_cleanup_handlers() { install(false); }

InterruptScope::InterruptScope() {
  g_signal.store(0);
  install(true);
}

InterruptScope::~InterruptScope() { install(false); }

FinishingScope::FinishingScope() {
  g_extra_signals.store(0);
  g_finishing.store(true);
}

FinishingScope::~FinishingScope() { g_finishing.store(false); }

int interrupt_signal() { return g_signal.load(); }

void clear_interrupt() { g_signal.store(0); }

std::string signal_name(int signal) {
  if (signal == SIGINT || signal == SIGTERM || signal == SIGHUP) return name_of(signal);
  return "signal " + std::to_string(signal);
}

Interrupted::Interrupted(int signal) : signal_(signal), message_("interrupted by " + signal_name(signal)) {}

void throw_if_interrupted() {
  if (const int signal = interrupt_signal()) throw Interrupted(signal);
}

namespace temp_files {

int add(const std::string& path) {
  if (path.size() + 1 > kMaxPath) return -1;
  for (int i = 0; i < kSlots; ++i) {
    int expected = 0;
    if (g_slots[i].state.compare_exchange_strong(expected, 1)) {
      std::memcpy(g_slots[i].path, path.c_str(), path.size() + 1);
      g_slots[i].state.store(2);
      return i;
    }
  }
  return -1;
}

void remove(int slot) {
  if (slot < 0 || slot >= kSlots) return;
  g_slots[slot].state.store(1);
  g_slots[slot].path[0] = '\0';
  g_slots[slot].state.store(0);
}

}  // namespace temp_files

}  // namespace crowdslam
