#include "server/job_lights.h"

#include <gtest/gtest.h>

namespace pdsm {
namespace {

TEST(EngineJobIds, ParseWhatTheyAreMadeFrom) {
  for (const auto& [light, count] : {std::pair(0, 1), std::pair(0, 3), std::pair(2, 3)}) {
    const std::string id = EngineJobId("0123abcd", light, count);
    for (const bool level : {false, true}) {
      const std::optional<EngineJobOf> of = ParseEngineJobId(level ? LevelEngineJobId(id) : id);
      ASSERT_TRUE(of) << id;
      EXPECT_EQ(of->job_id, "0123abcd");
      EXPECT_EQ(of->light, light);
      EXPECT_EQ(of->level, level) << id;
    }
  }
}

TEST(EngineJobIds, RefuseWhatTheyCannotHaveMade) {
  for (const char* id : {"j/x", "j/-1", "j/00001/other", "j/1x", "j/"}) {
    EXPECT_FALSE(ParseEngineJobId(id)) << id;
  }
}

}  // namespace
}  // namespace pdsm
