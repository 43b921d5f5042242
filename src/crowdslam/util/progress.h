#pragma once
// Progress of a long command on stderr: on a terminal one line redrawn in place (at most 4 times a
// second: done/total, rate, ETA and a detail such as the tracking state); otherwise a plain line every
// `plain_every` items (logs and CI output stay readable). Disabled: prints nothing (--quiet).
#include <chrono>
#include <cstddef>
#include <cstdio>
#include <string>

namespace crowdslam {

class ProgressLine {
 public:
  ProgressLine(bool enabled, size_t total, std::string unit, size_t plain_every = 100, std::FILE* out = stderr);
  ~ProgressLine();
  ProgressLine(const ProgressLine&) = delete;
  ProgressLine& operator=(const ProgressLine&) = delete;

  void update(size_t done, const std::string& detail);
  // Ends the redrawn line (newline) so that what follows starts on its own line.
  void finish();
  [[nodiscard]] bool on_terminal() const { return terminal_; }
  // The text of one progress line (without \r), e.g. "frame 120/927 (13 %)  41.2 frames/s  ETA 19 s  ok".
  static std::string format(size_t done, size_t total, const std::string& unit, double rate_per_s,
                            const std::string& detail);

 private:
  bool enabled_;
  size_t total_;
  std::string unit_;
  size_t plain_every_;
  std::FILE* out_;
  bool terminal_ = false;
  bool drawn_ = false;
  std::chrono::steady_clock::time_point start_, last_draw_;
};

}  // namespace crowdslam
