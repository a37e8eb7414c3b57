// pdsm-view on bad input: exit 2 and a message naming the file and the field.
#include <string>

#include <gtest/gtest.h>

#include "tests/view/view_test_support.h"

namespace pdsm::testing {
namespace {

CommandResult Headless(const std::string& example, const std::string& pdsm,
                       const std::string& extra, const TempDir& dir) {
  return RunView(example,
                 "--pdsm " + pdsm + " --headless --size 32x24 --screenshot " + dir.File("out.png") +
                     " " + extra,
                 dir);
}

TEST(ViewBadInput, CorruptPdsmNamesTheFile) {
  TempDir dir;
  std::string bytes = ReadBytes(SmallBake("plates"));
  ASSERT_GT(bytes.size(), 2000u);
  // Keep the EXR header, scramble the tile data.
  for (size_t i = bytes.size() / 2; i < bytes.size(); i += 7)
    bytes[i] = static_cast<char>(~bytes[i]);
  const std::string corrupt = dir.File("corrupt.exr");
  WriteText(corrupt, bytes);
  CommandResult r = Headless("plates", corrupt, "", dir);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("corrupt.exr"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir.File("out.png")));

  const std::string garbage = dir.File("garbage.exr");
  WriteText(garbage, "this is not an OpenEXR file");
  r = Headless("plates", garbage, "", dir);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("garbage.exr"), std::string::npos) << r.err;
}

TEST(ViewBadInput, PdsmOfAnotherSceneIsRefused) {
  TempDir dir;
  CommandResult r = Headless("sun_pillars", SmallBake("plates"), "", dir);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("scene_name"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("plates.exr"), std::string::npos) << r.err;
  // --allow-mismatch shows it anyway, with a warning.
  r = Headless("sun_pillars", SmallBake("plates"), "--allow-mismatch", dir);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("scene_name"), std::string::npos) << r.err;
}

TEST(ViewBadInput, LightEditedAfterTheBakeIsRefused) {
  TempDir dir;
  std::string scene = ReadBytes(ExamplePath("plates"));
  const std::string from = "\"size\": [3,3]";
  ASSERT_NE(scene.find(from), std::string::npos);
  scene.replace(scene.find(from), from.size(), "\"size\": [4,3]");
  const std::string edited = dir.File("scene.json");
  WriteText(edited, scene);
  CommandResult r =
      RunCommand(std::string(PDSM_VIEW) + " " + edited + " --pdsm " + SmallBake("plates") +
                     " --headless --screenshot " + dir.File("out.png"),
                 dir);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("light size"), std::string::npos) << r.err;
}

TEST(ViewBadInput, MissingFilesAndBadFlags) {
  TempDir dir;
  CommandResult r = Headless("plates", dir.File("nowhere.exr"), "", dir);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("nowhere.exr"), std::string::npos) << r.err;

  r = RunCommand(std::string(PDSM_VIEW) + " " + dir.File("none.json") + " --pdsm " +
                     SmallBake("plates") + " --headless --screenshot " + dir.File("o.png"),
                 dir);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("none.json"), std::string::npos) << r.err;

  r = Headless("plates", SmallBake("plates"), "--sphere 1,2,3", dir);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--sphere"), std::string::npos) << r.err;

  r = Headless("plates", SmallBake("plates"), "--mode soft", dir);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--mode"), std::string::npos) << r.err;

  r = Headless("plates", SmallBake("plates"), "--dynamic-combine sum", dir);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--dynamic-combine"), std::string::npos) << r.err;

  r = Headless("plates", SmallBake("plates"), "--dynamic-sm-count 0", dir);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--dynamic-sm-count"), std::string::npos) << r.err;

  WriteText(dir.File("tri.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  r = Headless(
      "plates", SmallBake("plates"),
      "--object " + dir.File("tri.obj") + " --object-transform 1,0,0,0,0,0,0,0,0,0,1,0,0,0,0,1",
      dir);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--object-transform[0]"), std::string::npos) << r.err;

  r = Headless("plates", SmallBake("plates"), "--object " + dir.File("no_mesh.ply"), dir);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--object[0]"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("no_mesh.ply"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace pdsm::testing
