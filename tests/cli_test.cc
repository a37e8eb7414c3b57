// The `pdsm` command line as a user runs it: exit codes 0 / 2 / 1, messages naming the file
// and field, no output left behind on failure, query and info output formats.
#include <cctype>
#include <filesystem>
#include <sstream>
#include <string>
#include <utility>

#include <gtest/gtest.h>

#include "core/bake/plan_fingerprint.h"
#include "core/pdsm/pdsm_image.h"
#include "core/util/version.h"
#include "tests/test_support.h"

namespace pdsm {
namespace {

using testing::CommandResult;
using testing::ExamplePath;
using testing::RunCommand;
using testing::TempDir;
using testing::WriteText;

const std::string kPdsm = PDSM_CLI;

constexpr const char* kGoodScene = testing::kTinySceneJson;

// A bad scene must exit 2, name the file and the field, and leave no output.
void ExpectBadScene(const std::string& json, const std::string& field) {
  TempDir dir;
  const std::string scene = dir.File("bad.json");
  WriteText(scene, json);
  const std::string out = dir.File("out.exr");
  const CommandResult r = RunCommand(kPdsm + " bake " + scene + " -o " + out, dir);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("bad.json"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(field), std::string::npos) << "expected field " << field << " in: " << r.err;
  EXPECT_FALSE(std::filesystem::exists(out));
  for (const auto& entry : std::filesystem::directory_iterator(dir.path())) {
    EXPECT_EQ(entry.path().filename().string().find(".exr"), std::string::npos)
        << "left behind: " << entry.path();
  }
}

std::string Replace(std::string text, const std::string& from, const std::string& to) {
  const size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return text.replace(at, from.size(), to);
}

TEST(Cli, BakeQueryInfoRoundTrip) {
  TempDir dir;
  const std::string scene = dir.File("tiny.json");
  WriteText(scene, kGoodScene);
  const std::string out = dir.File("tiny.exr");
  CommandResult r = RunCommand(kPdsm + " bake " + scene + " -o " + out, dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(std::filesystem::exists(out));
  EXPECT_TRUE(std::filesystem::exists(dir.File("tiny.png")));
  EXPECT_NE(r.err.find("vertices"), std::string::npos) << r.err;  // the closing summary

  const std::string points = dir.File("points.csv");
  // Under the plate's centre (umbra), far outside it (lit), behind the light (nan).
  WriteText(points, "0,0,0\n# comment\n\n4.5,0,4.5\n0,7,0\n");
  r = RunCommand(kPdsm + " query " + out + " --points " + points, dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out, "0,0,0,1.000000\n4.5,0,4.5,0.000000\n0,7,0,nan\n");

  r = RunCommand(kPdsm + " info " + out + " --json", dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("\"resolution\": [48, 48]"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\"samples\": 16"), std::string::npos) << r.out;
}

// pdsm info gives the light's size (rect: size, sun: angular diameter) and prints every number
// of its text with 6 significant digits; --json keeps them exact.
TEST(Cli, InfoGivesTheLightSizeWithSixDigits) {
  TempDir dir;
  const std::string rect = dir.File("rect.json"), sun = dir.File("sun.json");
  WriteText(rect, Replace(kGoodScene, "\"size\": [1,1]", "\"size\": [1.5,0.75]"));
  WriteText(sun, Replace(kGoodScene,
                         R"("rect": {"center": [0,6,0], "normal": [0,-1,0], "up": [0,0,1], )"
                         R"("size": [1,1]})",
                         R"("sun": {"direction": [-0.4,-1,-0.3], "angularDiameterDeg": 4})"));
  for (const std::string& scene : {rect, sun}) {
    ASSERT_EQ(
        RunCommand(kPdsm + " bake " + scene + " -o " + scene + ".exr --no-preview", dir).exit_code,
        0)
        << scene;
  }
  CommandResult r = RunCommand(kPdsm + " info " + rect + ".exr", dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("light       rect, size 1.5 x 0.75, centre [0, 6, 0], normal [0, -1, 0]"),
            std::string::npos)
      << r.out;
  r = RunCommand(kPdsm + " info " + sun + ".exr", dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("light       sun, 4 deg across, centre ["), std::string::npos) << r.out;
  // No number in the text has more than 6 significant digits (the sun's centre had 17); the
  // first line, which names the file (a temporary folder of many digits), aside.
  for (size_t i = r.out.find('\n'); i < r.out.size();) {
    if (!std::isdigit(static_cast<unsigned char>(r.out[i]))) {
      ++i;
      continue;
    }
    size_t digits = 0, j = i;
    bool leading = true;
    for (; j < r.out.size() &&
           (std::isdigit(static_cast<unsigned char>(r.out[j])) || r.out[j] == '.');
         ++j) {
      if (r.out[j] == '.') continue;
      if (leading && r.out[j] == '0') continue;
      leading = false;
      ++digits;
    }
    EXPECT_LE(digits, 6u) << r.out.substr(i, j - i) << " in " << r.out;
    i = j;
  }
  r = RunCommand(kPdsm + " info --json " + sun + ".exr", dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("\"angularDiameterDeg\": 4"), std::string::npos) << r.out;
  r = RunCommand(kPdsm + " info --json " + rect + ".exr", dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("\"lightSize\": [1.5, 0.75]"), std::string::npos) << r.out;
}

// The issue's case: a disk light 3 above a 100 x 100 floor bakes, but says that 53% of the
// floor (beyond 85 degrees off the light's axis: 1 - (6 tan 85 / 100)^2) gets no shadow, and
// what to do; a scene the frustum holds, or a light bounded by its own frustum, says nothing
// of the kind.
TEST(Cli, WarnsWhenReceiversFallOutsideTheFrustum) {
  TempDir dir;
  WriteText(dir.File("wide.json"), R"({
  "name": "wide",
  "meshes": [
    {"inline": {"positions": [-50,0,-50, 50,0,-50, 50,0,50, -50,0,50], "indices": [0,1,2, 0,2,3]},
     "role": "RECEIVER_ONLY"},
    {"inline": {"positions": [-1,1,-1, 1,1,-1, 1,1,1, -1,1,1], "indices": [0,1,2, 0,2,3]},
     "role": "CASTER_ONLY"}
  ],
  "light": {"disk": {"center": [0,3,0], "normal": [0,-1,0], "radius": 0.5}},
  "bake": {"resolution": [32,32], "samples": 4, "tileSize": 16}
})");
  CommandResult r = RunCommand(
      kPdsm + " bake " + dir.File("wide.json") + " -o " + dir.File("wide.exr") + " --no-preview",
      dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string warning = "pdsm: warning: ";
  const size_t at = r.err.find(warning);
  ASSERT_NE(at, std::string::npos) << r.err;
  EXPECT_NE(r.err.find("% of the receivers' area is outside the light's frustum", at),
            std::string::npos)
      << r.err;
  // The plan widens the window by 1e-3 of its size on each side, hence 52.8 here.
  const double percent = std::stod(r.err.substr(at + warning.size()));
  const double covered = 6 * 11.430052302761343 / 100;
  EXPECT_NEAR(percent, 100 * (1 - covered * covered), 0.5) << r.err;
  EXPECT_NE(r.err.find("move the light back"), std::string::npos) << r.err;
  WriteText(dir.File("far.csv"), "40,0,40\n");
  r = RunCommand(kPdsm + " query " + dir.File("wide.exr") + " --points " + dir.File("far.csv"),
                 dir);
  EXPECT_EQ(r.out, "40,0,40,nan\n") << r.err;

  // A light whose reach is bounded on purpose (an explicit frustum: a world's local light)
  // lights only that, and says nothing of the rest.
  std::string bounded = testing::ReadBytes(dir.File("wide.json"));
  const std::string knobs = R"("bake": {)";
  ASSERT_NE(bounded.find(knobs), std::string::npos);
  bounded.replace(bounded.find(knobs), knobs.size(),
                  R"("bake": {"frustum": {"window": [-1,1,-1,1], "depthRange": [0.5,4]}, )");
  WriteText(dir.File("bounded.json"), bounded);
  r = RunCommand(kPdsm + " bake " + dir.File("bounded.json") + " -o " + dir.File("bounded.exr") +
                     " --no-preview",
                 dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err.find("warning"), std::string::npos) << r.err;

  WriteText(dir.File("tiny.json"), kGoodScene);
  r = RunCommand(
      kPdsm + " bake " + dir.File("tiny.json") + " -o " + dir.File("tiny.exr") + " --no-preview",
      dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err.find("warning"), std::string::npos) << r.err;
}

TEST(Cli, BadPointsFileNamesFileAndLine) {
  TempDir dir;
  const std::string scene = dir.File("tiny.json");
  WriteText(scene, kGoodScene);
  const std::string out = dir.File("tiny.exr");
  ASSERT_EQ(RunCommand(kPdsm + " bake " + scene + " -o " + out, dir).exit_code, 0);
  WriteText(dir.File("pts.csv"), "1,2,3\n1,nan,3\n");
  const CommandResult r =
      RunCommand(kPdsm + " query " + out + " --points " + dir.File("pts.csv"), dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("pts.csv:2"), std::string::npos) << r.err;
}

// A header row "x,y,z" (as spreadsheets write it) is skipped before the first point, and only
// there; `--points -` reads standard input.
TEST(Cli, QueryTakesAHeaderRowAndStdin) {
  TempDir dir;
  const std::string scene = dir.File("tiny.json");
  WriteText(scene, kGoodScene);
  const std::string out = dir.File("tiny.exr");
  ASSERT_EQ(RunCommand(kPdsm + " bake " + scene + " -o " + out + " --no-preview", dir).exit_code,
            0);
  WriteText(dir.File("header.csv"), "# points\n X , y,Z\n0,0,0\n4.5,0,4.5\n");
  CommandResult r =
      RunCommand(kPdsm + " query " + out + " --points " + dir.File("header.csv"), dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out, "0,0,0,1.000000\n4.5,0,4.5,0.000000\n");

  r = RunCommand("cat " + dir.File("header.csv") + " | " + kPdsm + " query " + out + " --points -",
                 dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out, "0,0,0,1.000000\n4.5,0,4.5,0.000000\n");

  WriteText(dir.File("late.csv"), "0,0,0\nx,y,z\n");
  r = RunCommand("cat " + dir.File("late.csv") + " | " + kPdsm + " query " + out + " --points -",
                 dir);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("stdin:2"), std::string::npos) << r.err;
}

// pdsm query reads tiles on demand and answers points in the order of their tiles: the output
// still follows the input line by line, and a cache of 1 MiB (re-reading tiles) answers the
// same as the default one.
TEST(Cli, QueryAnswersInTheGivenOrderWhateverTheCache) {
  TempDir dir;
  const std::string scene = dir.File("tiny.json");
  WriteText(scene, kGoodScene);
  const std::string out = dir.File("tiny.exr");
  ASSERT_EQ(RunCommand(kPdsm + " bake " + scene + " -o " + out + " --no-preview", dir).exit_code,
            0);
  std::string points;
  std::vector<std::string> lines;
  for (int k = 0; k < 400; ++k) {  // scattered over the ground, tiles far apart in a row
    const double x = -4.5 + 9.0 * ((k * 37) % 400) / 400.0,
                 z = -4.5 + 9.0 * ((k * 91) % 400) / 400.0;
    lines.push_back(std::to_string(x) + ",0.2," + std::to_string(z));
    points += lines.back() + "\n";
  }
  WriteText(dir.File("pts.csv"), points);
  CommandResult big = RunCommand(kPdsm + " query " + out + " --points " + dir.File("pts.csv"), dir);
  ASSERT_EQ(big.exit_code, 0) << big.err;
  CommandResult small =
      RunCommand(kPdsm + " query " + out + " --cache-mib 1 --points " + dir.File("pts.csv"), dir);
  ASSERT_EQ(small.exit_code, 0) << small.err;
  EXPECT_EQ(small.out, big.out);
  std::istringstream answers(big.out);
  std::string answer;
  int shadowed = 0;
  for (const std::string& line : lines) {
    ASSERT_TRUE(std::getline(answers, answer));
    ASSERT_EQ(answer.substr(0, line.size() + 1), line + ",");
    if (answer.substr(line.size() + 1) != "0.000000") ++shadowed;
  }
  EXPECT_GT(shadowed, 10) << "some points must be in the plate's shadow";
  CommandResult bad =
      RunCommand(kPdsm + " query " + out + " --cache-mib 0 --points " + dir.File("pts.csv"), dir);
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("--cache-mib"), std::string::npos) << bad.err;
}

TEST(Cli, NotAPdsmFileExits2) {
  TempDir dir;
  WriteText(dir.File("fake.exr"), "definitely not an EXR file");
  WriteText(dir.File("pts.csv"), "1,2,3\n");
  CommandResult r = RunCommand(kPdsm + " info " + dir.File("fake.exr"), dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("fake.exr"), std::string::npos) << r.err;
  r = RunCommand(kPdsm + " info " + dir.File("missing.exr"), dir);
  EXPECT_EQ(r.exit_code, 2);
}

TEST(Cli, MalformedJson) { ExpectBadScene("{\"name\": \"x\", ", "invalid scene JSON"); }
TEST(Cli, UnknownField) { ExpectBadScene(Replace(kGoodScene, "\"meshes\"", "\"meshs\""), "meshs"); }
TEST(Cli, MissingMesh) {
  ExpectBadScene(Replace(kGoodScene, "{\"inline\": {\"positions\": [-1,2,-1",
                         "{\"path\": \"nowhere.ply\"}, {\"inline\": {\"positions\": [-1,2,-1"),
                 "meshes[1].path");
}
TEST(Cli, UnreadableMesh) {
  TempDir dir;
  WriteText(dir.File("garbage.ply"), "ply\nthis is not a mesh\n");
  // The path is absolute, so the scene written in another folder still finds it.
  ExpectBadScene(Replace(kGoodScene, "{\"inline\": {\"positions\": [-1,2,-1",
                         "{\"path\": \"" + dir.File("garbage.ply") +
                             "\"}, {\"inline\": {\"positions\": [-1,2,-1"),
                 "meshes[1].path");
}
TEST(Cli, NanCoordinate) {
  ExpectBadScene(Replace(kGoodScene, "[-1,2,-1,", "[\"NaN\",2,-1,"),
                 "meshes[1].inline.positions[0]");
}
TEST(Cli, InfiniteLightCenter) {
  ExpectBadScene(Replace(kGoodScene, "\"center\": [0,6,0]", "\"center\": [0,\"Infinity\",0]"),
                 "light.rect.center[1]");
}
TEST(Cli, ZeroLightSize) {
  ExpectBadScene(Replace(kGoodScene, "\"size\": [1,1]", "\"size\": [0,1]"), "light.rect.size");
}
TEST(Cli, NegativeLightSize) {
  ExpectBadScene(Replace(kGoodScene, "\"size\": [1,1]", "\"size\": [1,-2]"), "light.rect.size");
}
TEST(Cli, ZeroSamples) {
  ExpectBadScene(Replace(kGoodScene, "\"samples\": 16", "\"samples\": 0"), "bake.samples");
}
TEST(Cli, AbsurdSamples) {
  ExpectBadScene(Replace(kGoodScene, "\"samples\": 16", "\"samples\": 1000000"), "bake.samples");
}
TEST(Cli, AbsurdResolution) {
  ExpectBadScene(Replace(kGoodScene, "[48,48]", "[100000,48]"), "bake.resolution");
}
TEST(Cli, ZeroResolution) {
  ExpectBadScene(Replace(kGoodScene, "[48,48]", "[0,48]"), "bake.resolution");
}

TEST(Cli, BadOverrideFlagsExit2) {
  TempDir dir;
  const std::string scene = dir.File("tiny.json");
  WriteText(scene, kGoodScene);
  for (const std::string flags :
       {"--samples 0", "--resolution 12by4", "--epsilon 3", "--tile-size 0", "--samples 70000"}) {
    const CommandResult r =
        RunCommand(kPdsm + " bake " + scene + " -o " + dir.File("o.exr") + " " + flags, dir);
    EXPECT_EQ(r.exit_code, 2) << flags << ": " << r.err;
    EXPECT_FALSE(std::filesystem::exists(dir.File("o.exr"))) << flags;
  }
}

TEST(Cli, UnwritableOutputExits1OrTwoWithPath) {
  TempDir dir;
  const std::string scene = dir.File("tiny.json");
  WriteText(scene, kGoodScene);
  const CommandResult r =
      RunCommand(kPdsm + " bake " + scene + " -o /nonexistent-dir/x/out.exr", dir);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("/nonexistent-dir/x/out.exr"), std::string::npos) << r.err;
  // Says what to do, not which temporary name failed.
  EXPECT_NE(r.err.find("the folder /nonexistent-dir/x does not exist (create it first)"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(r.err.find(".tmp-"), std::string::npos) << r.err;
}

// The flag parser's errors too exit 2 with the "pdsm: " of every other error, and say where
// the flags are listed; --help still succeeds.
TEST(Cli, UsageErrorExits2) {
  TempDir dir;
  for (const std::string args :
       {" bake", " frobnicate", " bake x.json -o y.exr --samples abc", " query"}) {
    const CommandResult r = RunCommand(kPdsm + args, dir);
    EXPECT_EQ(r.exit_code, 2) << args;
    EXPECT_EQ(r.err.rfind("pdsm: ", 0), 0u) << args << ": " << r.err;
    EXPECT_NE(r.err.find("--help"), std::string::npos) << args << ": " << r.err;
  }
  const CommandResult help = RunCommand(kPdsm + " bake --help", dir);
  EXPECT_EQ(help.exit_code, 0) << help.err;
  EXPECT_NE(help.out.find("--no-preview"), std::string::npos) << help.out;
}

// Every binary answers --version on stdout with exit 0: the project version and the PDSM
// format it writes, as one line.
TEST(Cli, EveryBinaryPrintsItsVersion) {
  TempDir dir;
  for (const auto& [binary, name] : {std::pair<std::string, std::string>{PDSM_CLI, "pdsm"},
                                     {PDSM_COORDINATOR, "pdsm-coordinator"},
                                     {PDSM_WORKER, "pdsm-worker"},
                                     {PDSM_VIEW, "pdsm-view"}}) {
    CommandResult r = RunCommand(binary + " --version", dir);
    EXPECT_EQ(r.exit_code, 0) << name << ": " << r.err;
    EXPECT_EQ(r.out, VersionLine(name) + "\n") << name;
  }
  EXPECT_EQ(VersionLine("pdsm"), std::string("pdsm ") + std::string(ProjectVersion()) +
                                     " (commit " + std::string(GitCommit()) +
                                     "; PDSM file format 1-" + std::to_string(kPdsmFormatVersion) +
                                     "; plan fingerprint schema " +
                                     std::to_string(kPlanFingerprintSchema) + ")");
  EXPECT_FALSE(ProjectVersion().empty());
  // In a checkout, the commit is the one built (CMake re-reads it when HEAD moves).
  const std::string source = PDSM_SOURCE_DIR;
  if (std::filesystem::exists(source + "/.git")) {
    CommandResult head = RunCommand("git -C " + source + " rev-parse --short=12 HEAD", dir);
    ASSERT_EQ(head.exit_code, 0) << head.err;
    EXPECT_EQ(std::string(GitCommit()) + "\n", head.out);
  } else {
    EXPECT_EQ(GitCommit(), "unknown");
  }
}

}  // namespace
}  // namespace pdsm
