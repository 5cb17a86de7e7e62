#pragma once
// Reads the independent reference values of tests/data/reference (computed
// with et_simul 1.01 under Octave and checked by a 50-digit derivation; see
// its README) into rows keyed by column name.

#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace purkinje::testing {

class CsvRow {
 public:
  explicit CsvRow(std::map<std::string, std::string> cells) : cells_(std::move(cells)) {}
  double num(const std::string& key) const { return std::stod(str(key)); }
  const std::string& str(const std::string& key) const {
    auto it = cells_.find(key);
    if (it == cells_.end()) throw std::runtime_error("reference: no column " + key);
    return it->second;
  }

 private:
  std::map<std::string, std::string> cells_;
};

inline std::vector<std::string> split_csv_line(const std::string& line) {
  std::vector<std::string> out;
  std::string cell;
  bool quoted = false;
  for (char ch : line) {
    if (ch == '"') quoted = !quoted;
    else if (ch == ',' && !quoted) { out.push_back(cell); cell.clear(); }
    else if (ch != '\r') cell += ch;
  }
  out.push_back(cell);
  return out;
}

inline std::vector<CsvRow> read_reference(const std::string& file_name) {
  const std::string path = std::string(PURKINJE_REFERENCE_DIR) + "/" + file_name;
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open " + path);
  std::string line;
  std::getline(in, line);
  const std::vector<std::string> header = split_csv_line(line);
  std::vector<CsvRow> rows;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    const std::vector<std::string> cells = split_csv_line(line);
    std::map<std::string, std::string> m;
    for (size_t i = 0; i < header.size() && i < cells.size(); ++i) m[header[i]] = cells[i];
    rows.emplace_back(std::move(m));
  }
  return rows;
}

}  // namespace purkinje::testing
