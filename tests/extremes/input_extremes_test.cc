// NaN, infinity and out-of-range numbers anywhere in a scene file are refused with
// INVALID_ARGUMENT naming the file and the field, and `pdsm bake` exits 2 with that message.
#include <cctype>
#include <ostream>
#include <string>

#include <gtest/gtest.h>

#include "absl/strings/str_replace.h"
#include "core/scene/scene_loader.h"
#include "tests/test_support.h"

namespace pdsm::extremes {
namespace {

using pdsm::testing::TempDir;

// A valid scene with one placeholder per number under test; every case replaces one of them
// with a bad value and the others with good ones.
constexpr char kTemplate[] = R"({
  "name": "bad-numbers",
  "meshes": [
    {"inline": {"positions": [-3,0,-3, 3,0,-3, 3,0,3, -3,0,$POS], "indices": [0,1,2, 0,2,3]},
     "role": "RECEIVER_ONLY"},
    {"inline": {"positions": [-1,2.5,-1, 1,2.5,-1, 1,2.5,1], "indices": [0,1,2]},
     "transform": [1,0,0,$TX, 0,1,0,0, 0,0,1,0, 0,0,0,1]}
  ],
  "light": {"rect": {"center": [0,$CY,0], "normal": [0,-1,0], "up": [0,0,1],
                     "size": [$SIZE,1]}},
  "bake": {"resolution": [8,8], "samples": 4, "epsilon": $EPS, "depthBias": $BIAS,
           "frustum": {"window": [$WIN,0.7,-0.7,0.7], "depthRange": [1,6]}}
})";

struct BadNumber {
  const char* placeholder;
  const char* value;
  const char* field;  // what the message must name
};

void PrintTo(const BadNumber& bad, std::ostream* os) {
  *os << bad.placeholder + 1 << " = " << bad.value;
}

std::string SceneWith(const BadNumber& bad) {
  std::string text = kTemplate;
  const std::pair<const char*, const char*> good[] = {
      {"$POS", "3"},    {"$TX", "0"},       {"$CY", "5"},    {"$SIZE", "1"},
      {"$EPS", "0.01"}, {"$BIAS", "0.001"}, {"$WIN", "-0.7"}};
  for (const auto& [key, value] : good) {
    text =
        absl::StrReplaceAll(text, {{key, key == std::string(bad.placeholder) ? bad.value : value}});
  }
  return text;
}

const BadNumber kCases[] = {
    {"$POS", "\"NaN\"", "meshes[0].inline.positions"},
    {"$POS", "1e400", "meshes[0].inline.positions"},
    {"$TX", "\"Infinity\"", "meshes[1].transform"},
    {"$CY", "\"-Infinity\"", "light.rect.center"},
    {"$SIZE", "1e400", "light.rect.size"},
    {"$EPS", "\"NaN\"", "bake.epsilon"},
    {"$BIAS", "\"Infinity\"", "bake.depthBias"},
    {"$WIN", "\"NaN\"", "bake.frustum.window"},
};

class ExtremesInput : public ::testing::TestWithParam<BadNumber> {};

TEST_P(ExtremesInput, RefusedNamingTheField) {
  TempDir dir;
  const std::string path = dir.File("scene.json");
  pdsm::testing::WriteText(path, SceneWith(GetParam()));
  absl::StatusOr<Scene> scene = LoadSceneFile(path);
  ASSERT_FALSE(scene.ok()) << GetParam().placeholder << " = " << GetParam().value;
  EXPECT_EQ(scene.status().code(), absl::StatusCode::kInvalidArgument) << scene.status();
  EXPECT_NE(scene.status().message().find(path), std::string::npos) << scene.status();
  EXPECT_NE(scene.status().message().find(GetParam().field), std::string::npos) << scene.status();
}

// Test names say which placeholder and which value: "POS_NaN", "SIZE_1e400".
std::string CaseName(const ::testing::TestParamInfo<BadNumber>& info) {
  std::string name = std::string(info.param.placeholder + 1) + "_";
  for (const char* c = info.param.value; *c; ++c) {
    if (std::isalnum(static_cast<unsigned char>(*c))) name += *c;
    if (*c == '-') name += "minus";
  }
  return name;
}

INSTANTIATE_TEST_SUITE_P(Fields, ExtremesInput, ::testing::ValuesIn(kCases), CaseName);

// The template itself is valid: the refusals above come from the bad number alone.
TEST(ExtremesInputTemplate, GoodValuesLoad) {
  TempDir dir;
  const std::string path = dir.File("scene.json");
  pdsm::testing::WriteText(path, SceneWith({"", "", ""}));
  absl::StatusOr<Scene> scene = LoadSceneFile(path);
  EXPECT_TRUE(scene.ok()) << scene.status();
}

// `pdsm bake` on a NaN position: exit 2, the message names the field, no output file.
TEST(ExtremesInputCli, BakeExitsTwoNamingTheField) {
  TempDir dir;
  const std::string path = dir.File("scene.json");
  pdsm::testing::WriteText(path, SceneWith(kCases[0]));
  const pdsm::testing::CommandResult r = pdsm::testing::RunCommand(
      std::string(PDSM_CLI) + " bake " + path + " -o " + dir.File("out.exr"), dir);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("meshes[0].inline.positions"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir.File("out.exr")));
}

}  // namespace
}  // namespace pdsm::extremes
