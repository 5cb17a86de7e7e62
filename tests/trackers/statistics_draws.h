#pragma once
// How many noisy draws the statistical checks take: the calibration
// issue's 1000 unless PURKINJE_STATISTICS_DRAWS says fewer. .ci/run lowers
// it for the sanitizer and coverage builds, which check the code, not the
// bar (at 200 draws a standard deviation is still good to 5%).

#include <cstdlib>
#include <stdexcept>
#include <string>

namespace purkinje::trackers {

inline int statistics_draws() {
  constexpr long bar = 1000;
  const char* text = std::getenv("PURKINJE_STATISTICS_DRAWS");
  if (text == nullptr || *text == '\0') return bar;
  char* end = nullptr;
  const long n = std::strtol(text, &end, 10);
  if (*end != '\0' || n < 100 || n > bar) {
    throw std::invalid_argument(std::string("PURKINJE_STATISTICS_DRAWS = ") + text +
                                ": must be an integer in [100, 1000]");
  }
  return static_cast<int>(n);
}

}  // namespace purkinje::trackers
