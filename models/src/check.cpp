#include "purkinje/models/check.h"

#include <array>
#include <charconv>
#include <cmath>
#include <stdexcept>

namespace purkinje::check {

std::string format_number(double value) {
  std::array<char, 32> text{};
  const auto end = std::to_chars(text.data(), text.data() + text.size(), value).ptr;
  return std::string(text.data(), end);
}

void fail(const std::string& what, double value, const std::string& rule) {
  throw std::invalid_argument(what + " = " + format_number(value) + ": " + rule);
}

void require_positive(const std::string& what, double value) {
  if (!(std::isfinite(value) && value > 0)) fail(what, value, "must be finite and > 0");
}

void require_non_negative(const std::string& what, double value) {
  if (!(std::isfinite(value) && value >= 0)) fail(what, value, "must be finite and >= 0");
}

}  // namespace purkinje::check
