#pragma once
// Progress of a long command on stderr (`run`, `detect`, `vocab train`): on a terminal one line redrawn
// in place (at most 4 times a second: done/total, rate, ETA and a detail such as the tracking state);
// otherwise a plain line every `plain_every` items and a last one at the end, so logs and CI output stay
// readable. Disabled: prints nothing (--quiet).
#include <chrono>
#include <cstddef>
#include <cstdio>
#include <string>

namespace crowdslam {

class ProgressLine {
 public:
  // plain_every 0: a tenth of `total`, at most 100 (100 when the total is unknown).
  ProgressLine(bool enabled, size_t total, std::string unit, size_t plain_every = 0, std::FILE* out = stderr);
  ~ProgressLine();
  ProgressLine(const ProgressLine&) = delete;
  ProgressLine& operator=(const ProgressLine&) = delete;

  // Whether update(done, ...) would print now (callers that build an expensive detail call update only
  // then, and finish(done, detail) at the end).
  [[nodiscard]] bool due(size_t done) const;
  void update(size_t done, const std::string& detail);
  // Prints the last state if it was not shown (a plain line at the end; the final redraw on a terminal),
  // then ends the line. Called by the destructor. The second form first records `done` and `detail`.
  void finish();
  void finish(size_t done, const std::string& detail);
  // On a terminal: ends the redrawn line so that a log message can follow; the next update draws anew.
  void end_line();
  [[nodiscard]] bool on_terminal() const { return terminal_; }
  // The text of one progress line (without \r), e.g. "frame 120/927 (13 %)  41.2 frames/s  ETA 19 s  ok".
  static std::string format(size_t done, size_t total, const std::string& unit, double rate_per_s,
                            const std::string& detail);

 private:
  void print(size_t done, const std::string& detail);

  bool enabled_;
  size_t total_;
  std::string unit_;
  size_t plain_every_;
  std::FILE* out_;
  bool terminal_ = false;
  bool drawn_ = false;      // a terminal line is open
  bool finished_ = false;
  size_t last_done_ = 0;    // the newest update
  size_t shown_done_ = 0;   // the newest update printed
  std::string last_detail_;
  std::chrono::steady_clock::time_point start_, last_draw_;
};

}  // namespace crowdslam
