#include "core/scene/json_number_range.h"

#include <chrono>
#include <string>

#include <gtest/gtest.h>

namespace pdsm {
namespace {

TEST(FindOutOfRangeNumber, NamesTheFieldOfTheFirstNumberPastDouble) {
  const std::optional<OutOfRangeNumber> found = FindOutOfRangeNumber(
      R"({"name": "x", "meshes": [{"inline": {"positions": [0, 1, 2e3, -1e999]}}],
          "bake": {"epsilon": 1e400}})");
  ASSERT_TRUE(found);
  EXPECT_EQ(found->field, "meshes[0].inline.positions[3]");
  EXPECT_EQ(found->literal, "-1e999");
}

TEST(FindOutOfRangeNumber, NothingWhenEverythingFitsOrTheTextIsMalformed) {
  EXPECT_FALSE(FindOutOfRangeNumber(R"({"a": [1.5, {"b": -2e300}, [], {}], "c": true})"));
  EXPECT_FALSE(FindOutOfRangeNumber(R"({"a": [1, 2)"));
  EXPECT_FALSE(FindOutOfRangeNumber(R"({"a" 1e400})"));
  EXPECT_FALSE(FindOutOfRangeNumber(""));
}

TEST(FindOutOfRangeNumber, SiblingsAfterNestedContainersKeepTheirPaths) {
  const std::optional<OutOfRangeNumber> found =
      FindOutOfRangeNumber(R"({"a": {"b": [[1], [2, 3]]}, "c": [0, {"d": 1e500}]})");
  ASSERT_TRUE(found);
  EXPECT_EQ(found->field, "c[1].d");
}

// A 60 KB file of 30,000 nested arrays used to overflow the stack (SIGSEGV), and 20,000
// levels took seconds and hundreds of MB building a path per level.
TEST(FindOutOfRangeNumber, DeepNestingNeitherCrashesNorCostsMoreThanItsLength) {
  for (int depth : {20'000, 300'000}) {
    const std::string json =
        "{\"x\": " + std::string(depth, '[') + "1e999" + std::string(depth, ']') + "}";
    const auto start = std::chrono::steady_clock::now();
    EXPECT_FALSE(FindOutOfRangeNumber(json)) << "beyond the depth limit: left to the parser";
    EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(5));
  }
  const std::string shallow =
      "{\"x\": " + std::string(900, '[') + "1e999" + std::string(900, ']') + "}";
  const std::optional<OutOfRangeNumber> found = FindOutOfRangeNumber(shallow);
  ASSERT_TRUE(found);
  EXPECT_EQ(found->field.size(), 1 + 900 * 3);  // "x" then "[0]" per level
}

}  // namespace
}  // namespace pdsm
