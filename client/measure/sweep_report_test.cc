// The sweep's files (sweep.csv, reference.csv, sweep.png) are written through the one
// atomic-write path: a failure at any step leaves the previous file as it was.
#include "client/measure/sweep_report.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <string>
#include <vector>

#include "client/measure/accuracy_probe.h"
#include "client/measure/sweep_plot.h"
#include "core/scene/scene_loader.h"
#include "tests/test_support.h"
#include "tests/write_faults.h"

namespace pdsm {
namespace {

using ::testing::StartsWith;

std::vector<SweepRow> Rows(int count) {
  std::vector<SweepRow> rows(count);
  for (int i = 0; i < count; ++i) {
    BakeKnobs& k = rows[i].knobs;
    k.samples = 4 << (2 * i);
    k.width = k.height = 64;
    k.sm_resolution = 128;
    k.epsilon = 0.01;
    k.sampling = "sobol";
    rows[i].bake.seconds = 0.5 * (i + 1);
    rows[i].bake.peak_rss_bytes = 1u << 26;
    rows[i].bake.file_bytes = 1000;
    rows[i].errors.all.mean = 0.1 / (i + 1);
  }
  MarkParetoFront(&rows);
  return rows;
}

TEST(SweepCsv, EveryFailureLeavesThePreviousCsv) {
  testing::TempDir dir;
  const std::string path = dir.File("sweep.csv");
  ASSERT_TRUE(WriteSweepCsv(path, Rows(1)).ok());
  EXPECT_THAT(testing::ReadBytes(path), StartsWith(SweepCsvHeader() + "\n"));
  const std::vector<SweepRow> rows = Rows(3);
  testing::ExpectWriteFailuresLeaveTargetIntact(
      path, dir.path(), [&](FileSystem* fs) { return WriteSweepCsv(path, rows, fs); });
}

TEST(ReferenceCsv, EveryFailureLeavesThePreviousCsv) {
  absl::StatusOr<Scene> scene = LoadSceneFile(testing::ExamplePath("plates"));
  ASSERT_TRUE(scene.ok()) << scene.status();
  absl::StatusOr<AccuracyProbe> probe =
      AccuracyProbe::Create(*scene, AccuracyPointCounts{20, 20}, 1, {});
  ASSERT_TRUE(probe.ok()) << probe.status();
  testing::TempDir dir;
  const std::string path = dir.File("reference.csv");
  testing::WriteText(path, "kind,x,y,z,attenuation\n");
  testing::ExpectWriteFailuresLeaveTargetIntact(
      path, dir.path(), [&](FileSystem* fs) { return probe->WriteReferenceCsv(path, fs); });
  ASSERT_TRUE(probe->WriteReferenceCsv(path).ok());
  const std::string csv = testing::ReadBytes(path);
  EXPECT_THAT(csv, StartsWith("kind,x,y,z,attenuation\nsurface,"));
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'),
            1 + probe->points().surface.size() + probe->points().free_space.size());
}

// gnuplot prints the PNG; only the PNG is written (no script, no temporary image beside it).
TEST(SweepPlot, EveryFailureLeavesThePreviousPlot) {
  if (std::system("command -v gnuplot >/dev/null 2>&1") != 0) GTEST_SKIP() << "no gnuplot";
  testing::TempDir dir;
  const std::string csv = dir.File("sweep.csv");
  ASSERT_TRUE(WriteSweepCsv(csv, Rows(3)).ok());
  const std::string png = dir.File("sweep.png");
  testing::WriteText(png, "an older plot");
  testing::ExpectWriteFailuresLeaveTargetIntact(
      png, dir.path(), [&](FileSystem* fs) { return PlotSweep(csv, png, "plates", fs); });
  ASSERT_TRUE(PlotSweep(csv, png, "plates").ok());
  EXPECT_THAT(testing::ReadBytes(png), StartsWith("\x89PNG\r\n"));
}

}  // namespace
}  // namespace pdsm
