#include "purkinje/studies/simulation.h"

#include "purkinje/models/csv.h"

#include <cmath>
#include <exception>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>

#include "purkinje/models/check.h"

namespace purkinje::studies {

void Results::check_key(const std::string& key) const {
  if (key.empty()) throw std::invalid_argument("Results: an empty key");
  if (find(key)) throw std::invalid_argument("Results: key \"" + key + "\" added twice");
}

void Results::add(const std::string& key, double value, const std::string& unit) {
  check_key(key);
  if (!std::isfinite(value)) {
    throw std::invalid_argument("Results: \"" + key + "\" = " + check::format_number(value) + ": must be finite");
  }
  entries_.push_back({key, value, unit});
}

void Results::add(const std::string& key, const std::string& text) {
  check_key(key);
  entries_.push_back({key, text, ""});
}

void Results::add(const std::string& key, const std::vector<double>& values, const std::string& unit) {
  check_key(key);
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (!std::isfinite(values[i])) {
      throw std::invalid_argument("Results: \"" + key + "\"[" + std::to_string(i) + "] = " +
                                  check::format_number(values[i]) + ": must be finite");
    }
  }
  entries_.push_back({key, values, unit});
}

const Results::Entry* Results::find(const std::string& key) const {
  for (const Entry& e : entries_) {
    if (e.key == key) return &e;
  }
  return nullptr;
}

std::optional<double> Results::number(const std::string& key) const {
  const Entry* e = find(key);
  if (!e || !std::holds_alternative<double>(e->value)) return std::nullopt;
  return std::get<double>(e->value);
}

std::vector<SimulationRun> run_simulation(const std::vector<const Algorithm*>& algorithms,
                                          const std::vector<SimulationCase>& cases) {
  std::vector<SimulationRun> runs;
  for (const SimulationCase& c : cases) {
    for (const Algorithm* a : algorithms) {
      SimulationRun run;
      run.case_name = c.name;
      run.algorithm = a->name();
      try {
        run.results = a->run(c);
      } catch (const std::exception& e) {
        run.error = e.what();
      }
      runs.push_back(std::move(run));
    }
  }
  return runs;
}

namespace {

// Numbers as they read back exactly, lists in brackets.
std::string text_of(const Results::Value& value) {
  std::ostringstream out;
  out.precision(17);
  if (const double* x = std::get_if<double>(&value)) {
    out << *x;
  } else if (const std::string* s = std::get_if<std::string>(&value)) {
    out << *s;
  } else {
    const std::vector<double>& v = std::get<std::vector<double>>(value);
    out << '[';
    for (std::size_t i = 0; i < v.size(); ++i) out << (i ? ", " : "") << v[i];
    out << ']';
  }
  return out.str();
}


}  // namespace

std::string simulation_text(const std::vector<SimulationRun>& runs) {
  std::ostringstream out;
  for (const SimulationRun& run : runs) {
    out << run.case_name << " / " << run.algorithm << "\n";
    if (run.error) out << "  error: " << *run.error << "\n";
    for (const Results::Entry& e : run.results.entries()) {
      out << "  " << e.key << " = " << text_of(e.value) << (e.unit.empty() ? "" : " " + e.unit) << "\n";
    }
  }
  return out.str();
}

std::string simulation_json(const std::vector<SimulationRun>& runs) {
  using json = nlohmann::ordered_json;
  json out = {{"runs", json::array()}};
  for (const SimulationRun& run : runs) {
    json r = {{"case", run.case_name}, {"algorithm", run.algorithm}};
    json results = json::object(), units = json::object();
    for (const Results::Entry& e : run.results.entries()) {
      std::visit([&](const auto& v) { results[e.key] = v; }, e.value);
      if (!e.unit.empty()) units[e.key] = e.unit;
    }
    r["results"] = results;
    r["units"] = units;
    r["error"] = run.error ? json(*run.error) : json(nullptr);
    out["runs"].push_back(r);
  }
  return out.dump(2) + "\n";
}

std::string simulation_csv(const std::vector<SimulationRun>& runs) {
  std::string out = "case,algorithm,key,value,unit\n";
  const auto row = [&](const SimulationRun& run, const std::string& key, const std::string& value,
                       const std::string& unit) {
    out += csv_cell(run.case_name) + "," + csv_cell(run.algorithm) + "," + csv_cell(key) + "," + csv_cell(value) +
           "," + csv_cell(unit) + "\n";
  };
  for (const SimulationRun& run : runs) {
    if (run.error) row(run, "error", *run.error, "");
    for (const Results::Entry& e : run.results.entries()) row(run, e.key, text_of(e.value), e.unit);
  }
  return out;
}

}  // namespace purkinje::studies
