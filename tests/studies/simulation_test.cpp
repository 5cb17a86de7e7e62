// The simulation core: algorithms over cases, their results (every partial
// one) as text, JSON and CSV, and an algorithm's failure recorded without
// stopping the others.

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <stdexcept>
#include <string>

#include "purkinje/models/scene_file.h"
#include "purkinje/studies/simulation.h"

namespace purkinje::studies {
namespace {

// Reports what it was given: the number of frames and the first frame's
// scene name, and a point with its unit.
class Inventory final : public Algorithm {
 public:
  std::string name() const override { return "inventory"; }
  Results run(const SimulationCase& c) const override {
    Results r;
    r.add("frames", static_cast<double>(c.frames.size()));
    r.add("first_scene", c.frames.front().name);
    r.add("offset_mm", std::vector<double>{1.5, -2.25, 0}, "mm");
    return r;
  }
};

class RefusesBadCases final : public Algorithm {
 public:
  std::string name() const override { return "picky"; }
  Results run(const SimulationCase& c) const override {
    if (c.name == "bad") throw std::invalid_argument("cannot handle case 'bad'");
    Results r;
    r.add("ok", 1.0);
    return r;
  }
};

std::vector<SimulationCase> cases() {
  const Scene remote = load_scene(std::string(PURKINJE_SOURCE_DIR) + "/assets/scenes/remote.json");
  return {{"two frames", {remote, remote}}, {"bad", {remote}}};
}

TEST(Simulation, RunsEveryAlgorithmOverEveryCaseAndRecordsFailures) {
  const Inventory inventory;
  const RefusesBadCases picky;
  const std::vector<SimulationRun> runs = run_simulation({&inventory, &picky}, cases());
  ASSERT_EQ(runs.size(), 4u);  // case by case, each algorithm in order
  EXPECT_EQ(runs[0].case_name, "two frames");
  EXPECT_EQ(runs[0].algorithm, "inventory");
  EXPECT_EQ(runs[0].results.number("frames"), 2.0);
  EXPECT_EQ(runs[1].algorithm, "picky");
  EXPECT_FALSE(runs[1].error);
  EXPECT_EQ(runs[2].results.number("frames"), 1.0);
  ASSERT_TRUE(runs[3].error);
  EXPECT_EQ(*runs[3].error, "cannot handle case 'bad'");
  EXPECT_TRUE(runs[3].results.entries().empty());
}

TEST(Simulation, WritesEveryResultWithItsUnitAsTextAndJson) {
  const Inventory inventory;
  const RefusesBadCases picky;
  const std::vector<SimulationRun> runs = run_simulation({&inventory, &picky}, cases());
  const std::string text = simulation_text(runs);
  EXPECT_NE(text.find("two frames / inventory\n  frames = 2\n  first_scene = remote\n"
                      "  offset_mm = [1.5, -2.25, 0] mm\n"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("bad / picky\n  error: cannot handle case 'bad'\n"), std::string::npos) << text;

  const nlohmann::json j = nlohmann::json::parse(simulation_json(runs));
  ASSERT_EQ(j["runs"].size(), 4u);
  EXPECT_EQ(j["runs"][0]["results"]["frames"], 2.0);
  EXPECT_EQ(j["runs"][0]["results"]["offset_mm"], nlohmann::json({1.5, -2.25, 0.0}));
  EXPECT_EQ(j["runs"][0]["units"]["offset_mm"], "mm");
  EXPECT_TRUE(j["runs"][0]["error"].is_null());
  EXPECT_EQ(j["runs"][3]["error"], "cannot handle case 'bad'");
  // Keys in the order the algorithm added them.
  const nlohmann::ordered_json ordered = nlohmann::ordered_json::parse(simulation_json(runs));
  EXPECT_EQ(ordered["runs"][0]["results"].begin().key(), "frames");
}

// The CSV, expected line by line as written by hand: a row per result, the
// list quoted (it holds commas), the failed run's message as its "error".
TEST(Simulation, WritesEveryResultAsACsvRow) {
  const Inventory inventory;
  const RefusesBadCases picky;
  const std::vector<SimulationRun> runs = run_simulation({&inventory, &picky}, cases());
  EXPECT_EQ(simulation_csv(runs),
            "case,algorithm,key,value,unit\n"
            "two frames,inventory,frames,2,\n"
            "two frames,inventory,first_scene,remote,\n"
            "two frames,inventory,offset_mm,\"[1.5, -2.25, 0]\",mm\n"
            "two frames,picky,ok,1,\n"
            "bad,inventory,frames,1,\n"
            "bad,inventory,first_scene,remote,\n"
            "bad,inventory,offset_mm,\"[1.5, -2.25, 0]\",mm\n"
            "bad,picky,error,cannot handle case 'bad',\n");
  // A text with a quote and a line break stays one cell.
  Results r;
  r.add("note", "said \"no\"\nthen left");
  const std::vector<SimulationRun> one = {{"c", "a", r, std::nullopt}};
  EXPECT_EQ(simulation_csv(one), "case,algorithm,key,value,unit\nc,a,note,\"said \"\"no\"\"\nthen left\",\n");
}

TEST(Simulation, ResultsRefuseRepeatedKeysAndNumbersThatAreNotFinite) {
  Results r;
  r.add("radius_mm", 7.8, "mm");
  EXPECT_THROW(r.add("radius_mm", 7.9, "mm"), std::invalid_argument);
  EXPECT_THROW(r.add("", 1.0), std::invalid_argument);
  try {
    r.add("depth_mm", std::nan(""), "mm");
    ADD_FAILURE() << "NaN accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("depth_mm"), std::string::npos) << e.what();
  }
  EXPECT_THROW(r.add("point_mm", std::vector<double>{1, INFINITY}, "mm"), std::invalid_argument);
  EXPECT_EQ(r.number("radius_mm"), 7.8);
  EXPECT_FALSE(r.number("depth_mm"));
  r.add("note", std::string("radius from a prior"));
  EXPECT_FALSE(r.number("note"));  // a text, not a number
  EXPECT_EQ(r.entries().size(), 2u);
}

}  // namespace
}  // namespace purkinje::studies
