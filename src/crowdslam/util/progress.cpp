#include "crowdslam/util/progress.h"

#include <unistd.h>

#include <cmath>

namespace crowdslam {

ProgressLine::ProgressLine(bool enabled, size_t total, std::string unit, size_t plain_every, std::FILE* out)
    : enabled_(enabled), total_(total), unit_(std::move(unit)), plain_every_(plain_every > 0 ? plain_every : 1), out_(out) {
  terminal_ = enabled_ && out_ && ::isatty(::fileno(out_)) == 1;
  start_ = last_draw_ = std::chrono::steady_clock::now();
}

ProgressLine::~ProgressLine() { finish(); }

std::string ProgressLine::format(size_t done, size_t total, const std::string& unit, double rate_per_s,
                                 const std::string& detail) {
  char buffer[256];
  std::string text;
  if (total > 0) {
    std::snprintf(buffer, sizeof buffer, "%s %zu/%zu (%.0f %%)", unit.c_str(), done, total,
                  100.0 * static_cast<double>(done) / static_cast<double>(total));
  } else {
    std::snprintf(buffer, sizeof buffer, "%s %zu", unit.c_str(), done);
  }
  text = buffer;
  if (rate_per_s > 0) {
    std::snprintf(buffer, sizeof buffer, "  %.1f %ss/s", rate_per_s, unit.c_str());
    text += buffer;
    if (total > done) {
      std::snprintf(buffer, sizeof buffer, "  ETA %.0f s", std::ceil(static_cast<double>(total - done) / rate_per_s));
      text += buffer;
    }
  }
  if (!detail.empty()) text += "  " + detail;
  return text;
}

void ProgressLine::update(size_t done, const std::string& detail) {
  if (!enabled_) return;
  const auto now = std::chrono::steady_clock::now();
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  const double rate = elapsed > 0 ? static_cast<double>(done) / elapsed : 0.0;
  if (terminal_) {
    if (std::chrono::duration<double>(now - last_draw_).count() < 0.25 && done != total_) return;
    last_draw_ = now;
    // \r back to the start, the line, then clear to its end (a shorter line leaves nothing behind).
    std::fprintf(out_, "\r%s\033[K", format(done, total_, unit_, rate, detail).c_str());
    std::fflush(out_);
    drawn_ = true;
  } else if (done > 0 && done % plain_every_ == 0) {
    std::fprintf(out_, "%s\n", format(done, total_, unit_, rate, detail).c_str());
    std::fflush(out_);
  }
}

void ProgressLine::finish() {
  if (terminal_ && drawn_) {
    std::fprintf(out_, "\n");
    std::fflush(out_);
  }
  drawn_ = false;
}

}  // namespace crowdslam
