#include "progress.h"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <utility>

namespace purkinje::tools {

namespace {

std::string minutes_seconds(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0) return "?";
  const long s = std::lround(seconds);
  char text[32];
  std::snprintf(text, sizeof text, "%ld:%02ld", s / 60, s % 60);
  return text;
}

}  // namespace

Progress::Progress(std::string label, std::size_t total, bool quiet)
    : label_(std::move(label)),
      total_(total),
      quiet_(quiet),
      terminal_(isatty(STDERR_FILENO) != 0),
      start_(std::chrono::steady_clock::now()),
      last_shown_(start_) {}

Progress::~Progress() {
  if (!quiet_ && terminal_ && shown_) std::fprintf(stderr, "\r\033[K");
}

void Progress::step() {
  ++done_;
  if (quiet_) return;
  const auto now = std::chrono::steady_clock::now();
  if (terminal_ && done_ < total_ && now - last_shown_ < std::chrono::milliseconds(100)) return;
  // A log gets a line per step, or per percent beyond 100 steps: a
  // million-image shard must not write a million lines.
  if (!terminal_ && total_ > 100 && done_ < total_ && done_ * 100 / total_ == (done_ - 1) * 100 / total_) return;
  last_shown_ = now;
  show(!terminal_);
}

void Progress::show(bool whole_line) {
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  const double rate = elapsed > 0 ? static_cast<double>(done_) / elapsed : 0;
  const double left = rate > 0 ? static_cast<double>(total_ - done_) / rate : -1;
  std::fprintf(stderr, "%s%s: %zu/%zu, %.3g per s, ETA %s%s", whole_line ? "" : "\r\033[K", label_.c_str(), done_,
               total_, rate, minutes_seconds(left).c_str(), whole_line ? "\n" : "");
  std::fflush(stderr);
  shown_ = true;
}

}  // namespace purkinje::tools
