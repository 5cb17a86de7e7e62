#pragma once
// CSV cells as RFC 4180 writes them: the labels, scores, detections,
// simulation results and data-set tables share this one rule.

#include <string>

namespace purkinje {

// The text as one cell: quoted, with its quotes doubled, when it holds a
// comma, a quote or a line break.
inline std::string csv_cell(const std::string& text) {
  if (text.find_first_of(",\"\r\n") == std::string::npos) return text;
  std::string quoted = "\"";
  for (const char c : text) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
  return quoted + "\"";
}

}  // namespace purkinje
