#pragma once
// Checks of options and model parameters: a failure throws
// std::invalid_argument naming the thing, its value and the rule, with one
// number format everywhere (the shortest text that reads back as the same
// double: "0.005" and "-1e-09", never "0.0050000000000000001" or
// std::to_string's "-0.000000").

#include <string>

namespace purkinje::check {

std::string format_number(double value);

[[noreturn]] void fail(const std::string& what, double value, const std::string& rule);

// Finite and > 0, or finite and >= 0; else fail(what, value, the rule).
void require_positive(const std::string& what, double value);
void require_non_negative(const std::string& what, double value);

}  // namespace purkinje::check
