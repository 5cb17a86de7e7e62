#pragma once
// A count that a test's bar fixes and CI may lower through an environment
// variable (.ci/run: the sanitizer and coverage phases check the code, not
// the bar, and cut the realism renders and the statistical draws).

#include <cstdlib>
#include <stdexcept>
#include <string>

namespace purkinje::testing {

// `bar` unless `variable` is set; then an integer in [minimum, bar], or
// std::invalid_argument naming the variable, its value and the range.
inline int count_from_environment(const char* variable, int bar, int minimum) {
  const char* text = std::getenv(variable);
  if (text == nullptr || *text == '\0') return bar;
  char* end = nullptr;
  const long n = std::strtol(text, &end, 10);
  if (*end != '\0' || n < minimum || n > bar) {
    throw std::invalid_argument(std::string(variable) + " = " + text + ": must be an integer in [" +
                                std::to_string(minimum) + ", " + std::to_string(bar) + "]");
  }
  return static_cast<int>(n);
}

}  // namespace purkinje::testing
