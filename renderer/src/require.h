#pragma once
// Argument checks shared inside the renderer: a failure throws
// std::invalid_argument naming the thing, its value and the rule.

#include <array>
#include <charconv>
#include <cmath>
#include <stdexcept>
#include <string>

namespace purkinje::renderer::detail {

// Shortest text that reads back as the same double ("0.005", not
// "0.0050000000000000001").
inline std::string format_number(double value) {
  std::array<char, 32> text{};
  const auto end = std::to_chars(text.data(), text.data() + text.size(), value).ptr;
  return std::string(text.data(), end);
}

[[noreturn]] inline void fail(const std::string& what, double value, const std::string& rule) {
  throw std::invalid_argument(what + " = " + format_number(value) + ": " + rule);
}

inline void require_positive(const std::string& what, double value) {
  if (!(std::isfinite(value) && value > 0)) fail(what, value, "must be finite and > 0");
}

inline void require_non_negative(const std::string& what, double value) {
  if (!(std::isfinite(value) && value >= 0)) fail(what, value, "must be finite and >= 0");
}

}  // namespace purkinje::renderer::detail
