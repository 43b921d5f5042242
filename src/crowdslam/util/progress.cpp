#include "crowdslam/util/progress.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>

namespace crowdslam {

namespace {
constexpr double kRedrawInterval_s = 0.25;
constexpr size_t kMaxPlainEvery = 100;

size_t auto_plain_every(size_t total) {
  if (total == 0) return kMaxPlainEvery;
  return std::clamp<size_t>((total + 9) / 10, 1, kMaxPlainEvery);
}
}  // namespace

ProgressLine::ProgressLine(bool enabled, size_t total, std::string unit, size_t plain_every, std::FILE* out)
    : enabled_(enabled && out != nullptr),
      total_(total),
      unit_(std::move(unit)),
      plain_every_(plain_every > 0 ? plain_every : auto_plain_every(total)),
      out_(out) {
  terminal_ = enabled_ && ::isatty(::fileno(out_)) == 1;
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

bool ProgressLine::due(size_t done) const {
  if (!enabled_ || finished_) return false;
  if (!terminal_) return done > 0 && done % plain_every_ == 0 && done != shown_done_;
  const double since_draw = std::chrono::duration<double>(std::chrono::steady_clock::now() - last_draw_).count();
  return since_draw >= kRedrawInterval_s || done == total_ || !drawn_;
}

void ProgressLine::update(size_t done, const std::string& detail) {
  if (!enabled_ || finished_) return;
  last_done_ = done;
  last_detail_ = detail;
  if (due(done)) print(done, detail);
}

void ProgressLine::print(size_t done, const std::string& detail) {
  const auto now = std::chrono::steady_clock::now();
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  const double rate = elapsed > 0 ? static_cast<double>(done) / elapsed : 0.0;
  const std::string text = format(done, total_, unit_, rate, detail);
  if (terminal_) {
    // \r back to the start, the line, then clear to its end (a shorter line leaves nothing behind).
    std::fprintf(out_, "\r%s\033[K", text.c_str());
    drawn_ = true;
  } else {
    std::fprintf(out_, "%s\n", text.c_str());
  }
  std::fflush(out_);
  last_draw_ = now;
  shown_done_ = done;
}

void ProgressLine::end_line() {
  if (terminal_ && drawn_) {
    std::fprintf(out_, "\n");
    std::fflush(out_);
  }
  drawn_ = false;
}

void ProgressLine::finish(size_t done, const std::string& detail) {
  if (!enabled_ || finished_) return;
  last_done_ = done;
  last_detail_ = detail;
  finish();
}

void ProgressLine::finish() {
  if (!enabled_ || finished_) return;
  if (last_done_ > 0 && last_done_ != shown_done_) print(last_done_, last_detail_);
  end_line();
  finished_ = true;
}

}  // namespace crowdslam
