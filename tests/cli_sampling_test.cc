// `pdsm bake --sampling / --adaptive-tolerance / --adaptive-min-samples` and what `pdsm info`
// says about the result.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "tests/test_support.h"

namespace pdsm {
namespace {

using testing::CommandResult;
using testing::ExamplePath;
using testing::RunCommand;
using testing::TempDir;

const std::string kPdsm = PDSM_CLI;
const std::string kSmallBake = " --resolution 32x32 --tile-size 8 --sm-resolution 256 --no-preview";

TEST(CliSampling, EveryPatternBakes) {
  TempDir dir;
  for (const std::string name : {"stratified", "uniform", "sobol", "halton", "blue-noise"}) {
    const std::string out = dir.File(name + ".exr");
    CommandResult r = RunCommand(kPdsm + " bake " + ExamplePath("plates") + " -o " + out +
                                     kSmallBake + " --samples 8 --sampling " + name,
                                 dir);
    ASSERT_EQ(r.exit_code, 0) << name << ": " << r.err;
    r = RunCommand(kPdsm + " info --json " + out, dir);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find("\"samples\": 8"), std::string::npos) << r.out;
    // pdsm info names the pattern as --sampling takes it, and the seed.
    EXPECT_NE(r.out.find("\"sampling\": \"" + name + "\", \"seed\": \"1\""), std::string::npos)
        << r.out;
    r = RunCommand(kPdsm + " info " + out, dir);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find("8 samples (" + name + ", seed 1)"), std::string::npos) << r.out;
  }
}

TEST(CliSampling, UnknownPatternIsBadInput) {
  TempDir dir;
  const std::string out = dir.File("x.exr");
  const CommandResult r = RunCommand(
      kPdsm + " bake " + ExamplePath("plates") + " -o " + out + " --sampling sobolish", dir);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--sampling"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(out));
}

TEST(CliSampling, AdaptiveWithStratifiedIsBadInput) {
  TempDir dir;
  const std::string out = dir.File("x.exr");
  const CommandResult r = RunCommand(kPdsm + " bake " + ExamplePath("plates") + " -o " + out +
                                         " --sampling stratified --adaptive-tolerance 0.05",
                                     dir);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("bake.sampling"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(out));
}

TEST(CliSampling, AdaptiveBakeReportsTileSamples) {
  TempDir dir;
  const std::string out = dir.File("a.exr");
  CommandResult r =
      RunCommand(kPdsm + " bake " + ExamplePath("plates") + " -o " + out + kSmallBake +
                     " --samples 64 --adaptive-tolerance 0.05 "
                     "--adaptive-min-samples 8",
                 dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("adaptive sampling: tolerance 0.05"), std::string::npos) << r.err;
  r = RunCommand(kPdsm + " info " + out, dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("adaptive    tolerance 0.05, first batch 8; samples per tile min 8"),
            std::string::npos)
      << r.out;
  r = RunCommand(kPdsm + " info --json " + out, dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("\"adaptiveTolerance\": 0.050000000000000003"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\"tileSamples\": {\"min\": 8"), std::string::npos) << r.out;
}

}  // namespace
}  // namespace pdsm
