// The temporaries outputs go through, and the names a resumed run may
// remove; misspelling hints.

#include "purkinje/models/output_file.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <string>

#include "purkinje/models/spelling.h"

namespace purkinje {
namespace {

TEST(Temporaries, AreHiddenSiblingsNamedAfterTheTargetAndThisProcess) {
  const auto dir = std::filesystem::temp_directory_path() / ("purkinje_temporaries_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const auto t = create_temporary(dir / "a.b.png");
  EXPECT_EQ(t.parent_path(), dir);
  const std::string name = t.filename().string();
  EXPECT_EQ(name.rfind(".a.b.png.tmp." + std::to_string(::getpid()) + ".", 0), 0u) << name;
  EXPECT_TRUE(is_temporary_name(name));
  EXPECT_EQ(temporary_owner(name), ::getpid());
  EXPECT_TRUE(std::filesystem::is_regular_file(t));
  release_temporary(t);
  std::filesystem::remove_all(dir);
}

TEST(Temporaries, OnlyTheirNamesAreTakenForThem) {
  EXPECT_TRUE(is_temporary_name(".x.png.tmp.123.0"));
  EXPECT_TRUE(is_temporary_name(".variations.csv.tmp.99999.41"));
  for (const char* other : {"x.png.tmp.123.0", ".x.png.tmp.123.", ".x.png.tmp..0", ".x.png.tmp.12a.0",
                            ".tmp.1.2", ".x.png.tmp-123-0", ".x.png", "score.json", ".x.png.tmp.123"}) {
    EXPECT_FALSE(is_temporary_name(other)) << other;
  }
  EXPECT_EQ(temporary_owner(".x.png.tmp.123.0"), 123);
  EXPECT_FALSE(temporary_owner(".x.png.tmp.99999999999999999999999.0")) << "no process has that id";
  {
  }
}

TEST(Spelling, SuggestsTheClosestCandidateWithinTwoEditsOrAPrefix) {
  const std::vector<std::string> subcommands = {"truth", "render", "track", "score", "calibrate"};
  EXPECT_EQ(closest_match("rendr", subcommands), "render");
  EXPECT_EQ(closest_match("calibrat", subcommands), "calibrate");
  EXPECT_EQ(closest_match("trak", subcommands), "track");
  EXPECT_FALSE(closest_match("frobnicate", subcommands));
  EXPECT_FALSE(closest_match("", subcommands));
  EXPECT_EQ(closest_match("confidance", {"confidence", "image"}), "confidence");
}

}  // namespace
}  // namespace purkinje
