#pragma once
// The simulation core (the seed framework's spine): algorithms are strategies
// with one method that takes the frames of a case (one scene, or the same
// rig with the eye in several places) and returns named results, every
// partial result among them; the core runs a list of algorithms over a
// list of cases and writes what they returned as text, JSON and CSV.

#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "purkinje/models/scene.h"

namespace purkinje::studies {

// An algorithm's results in the order it added them: numbers, texts and
// lists of numbers (a point, a covariance row by row), each with its unit.
// Keys are unique; a number must be finite (NaN is a result nobody can
// use: an algorithm says why there is none in a text instead).
class Results {
 public:
  using Value = std::variant<double, std::string, std::vector<double>>;
  struct Entry {
    std::string key;
    Value value;
    std::string unit;  // "" for none
  };

  // Each throws std::invalid_argument for a key already added, an empty
  // key, or a number that is not finite, naming the key.
  void add(const std::string& key, double value, const std::string& unit = "");
  void add(const std::string& key, const std::string& text);
  void add(const std::string& key, const std::vector<double>& values, const std::string& unit = "");

  const std::vector<Entry>& entries() const { return entries_; }
  const Entry* find(const std::string& key) const;
  std::optional<double> number(const std::string& key) const;

 private:
  void check_key(const std::string& key) const;
  std::vector<Entry> entries_;
};

// The frames of one case: the same rig, the eye where each frame puts it.
struct SimulationCase {
  std::string name;
  std::vector<Scene> frames;
};

class Algorithm {
 public:
  virtual ~Algorithm() = default;
  virtual std::string name() const = 0;
  // Throws for a case it cannot handle; the core records the message.
  virtual Results run(const SimulationCase& c) const = 0;
};

// One algorithm over one case: its results, or why there are none.
struct SimulationRun {
  std::string case_name, algorithm;
  Results results;
  std::optional<std::string> error;
};

// Every algorithm over every case, case by case; an algorithm that throws
// gets its message recorded and the others go on.
std::vector<SimulationRun> run_simulation(const std::vector<const Algorithm*>& algorithms,
                                          const std::vector<SimulationCase>& cases);

// For people: a block per run, one result per line with its unit.
std::string simulation_text(const std::vector<SimulationRun>& runs);
// For programs: {"runs": [{"case", "algorithm", "results": {key: value},
// "units": {key: unit}, "error"}]}, keys in the order added.
std::string simulation_json(const std::vector<SimulationRun>& runs);
// For tables (pandas, R, a spreadsheet): one row per result,
// "case,algorithm,key,value,unit", numbers as in the text (they read back
// exactly), a list as "[a, b, c]"; a run that failed has one row with key
// "error" and the message as its value. Cells are quoted as RFC 4180 says.
std::string simulation_csv(const std::vector<SimulationRun>& runs);

}  // namespace purkinje::studies
