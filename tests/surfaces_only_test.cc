// Surfaces-only bakes (bake.surfacesOnly, `pdsm bake --surfaces-only`): the file keeps A(z)
// only in thin depth windows around the receivers. On receiver surfaces it answers exactly as
// the full bake does, it is smaller, free space reads NaN, and it is deterministic locally and
// through the service.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "core/pdsm/pdsm_file.h"
#include "core/pdsm/pdsm_query.h"
#include "core/scene/scene_loader.h"
#include "tests/service/service_cluster.h"
#include "tests/test_support.h"
#include "worker/local_bake.h"

namespace pdsm {
namespace {

using testing::ExamplePath;
using testing::ReadBytes;
using testing::TempDir;

struct Baked {
  BakeSummary summary;
  PdsmImage image;
  std::string bytes;
};

Baked BakePlates(bool surfaces_only, double epsilon, const TempDir& dir, const std::string& name,
                 int threads = 2, int samples_per_task = 0) {
  pdsm::v1::BakeParams overrides;
  overrides.add_resolution(128);
  overrides.add_resolution(128);
  overrides.set_samples(32);
  overrides.set_epsilon(epsilon);
  overrides.set_tile_size(32);
  if (surfaces_only) overrides.set_surfaces_only(true);
  absl::StatusOr<Scene> scene = LoadSceneFile(ExamplePath("plates"), overrides);
  EXPECT_TRUE(scene.ok()) << scene.status();
  LocalBakeOptions options;
  options.output_path = dir.File(name);
  options.threads = threads;
  options.samples_per_task = samples_per_task;
  absl::StatusOr<BakeSummary> summary = RunLocalBake(*scene, options);
  EXPECT_TRUE(summary.ok()) << summary.status();
  absl::StatusOr<PdsmImage> image = ReadPdsm(options.output_path);
  EXPECT_TRUE(image.ok()) << image.status();
  if (!summary.ok() || !image.ok()) return {};
  return Baked{*summary, *std::move(image), ReadBytes(options.output_path)};
}

// Points on the receivers of examples/plates: the ground, the top of the triangle plate at
// y = 2 and of the square plate at y = 4.
std::vector<glm::dvec3> ReceiverPoints() {
  std::vector<glm::dvec3> points;
  for (int i = 0; i < 40; ++i) {
    for (int j = 0; j < 40; ++j)
      points.emplace_back(-6 + 12 * (i + 0.5) / 40, 0, -6 + 12 * (j + 0.5) / 40);
  }
  for (int k = 0; k < 200; ++k) {
    const double u = (k % 20 + 0.5) / 20.0, v = (k / 20 + 0.5) / 10.0;
    points.emplace_back(0.5 + 2.0 * u * (1 - v) + v * 1.0, 2.0, 0.5 + 1.8 * v);
  }
  for (int k = 0; k < 200; ++k) {
    points.emplace_back(-3 + 3 * (k % 20 + 0.5) / 20.0, 4.0, -2.5 + 3 * (k / 20 + 0.5) / 10.0);
  }
  return points;
}

// With epsilon = 0, receiver answers are the full bake's (up to one sample, see below).
TEST(SurfacesOnly, AnswersAsTheFullBakeOnReceiversLossless) {
  TempDir dir;
  const Baked full = BakePlates(false, 0.0, dir, "full.exr");
  const Baked surfaces = BakePlates(true, 0.0, dir, "surfaces.exr");
  EXPECT_FALSE(full.image.header.surfaces_only);
  EXPECT_TRUE(surfaces.image.header.surfaces_only);
  double max_diff = 0;
  int compared = 0, shadowed = 0, differing = 0;
  for (const glm::dvec3& p : ReceiverPoints()) {
    const double a = QueryAttenuation(full.image, p);
    const double b = QueryAttenuation(surfaces.image, p);
    ASSERT_FALSE(std::isnan(a));
    ASSERT_FALSE(std::isnan(b)) << "receiver point " << p.x << "," << p.y << "," << p.z;
    max_diff = std::max(max_diff, std::abs(a - b));
    differing += std::abs(a - b) > 1e-6;
    shadowed += a > 0;
    ++compared;
  }
  std::printf(
      "lossless: max |surfaces - full| %.2e, %d of %d points differ (%d shadowed); "
      "bytes %zu -> %zu\n",
      max_diff, differing, compared, shadowed, full.bytes.size(), surfaces.bytes.size());
  EXPECT_GT(shadowed, 300);
  // Inside a window the per-sample shadow test is the full bake's. The shadow maps cover
  // smaller windows, though, and a texel centre lying on a caster's edge can rasterize the
  // other way in another window: at most one sample of one pixel flips. Measured: 1 point of
  // 2000 differs, by 0.0090 (0.29 x 1/32).
  EXPECT_LE(max_diff, 1.0 / 32 + 1e-6);
  EXPECT_LE(differing, compared / 200);
  EXPECT_LT(surfaces.bytes.size(), full.bytes.size());
  // Free space under the square plate, in its umbra, is not kept: NaN.
  EXPECT_TRUE(std::isnan(QueryAttenuation(surfaces.image, {-1.5, 1.0, -1.0})));
  EXPECT_FALSE(std::isnan(QueryAttenuation(full.image, {-1.5, 1.0, -1.0})));
}

TEST(SurfacesOnly, WithinTwoEpsilonOfTheFullBakeAndSmaller) {
  TempDir dir;
  constexpr double kEpsilon = 0.01;
  const Baked full = BakePlates(false, kEpsilon, dir, "full.exr");
  const Baked surfaces = BakePlates(true, kEpsilon, dir, "surfaces.exr");
  double max_diff = 0;
  for (const glm::dvec3& p : ReceiverPoints()) {
    const double surface = QueryAttenuation(surfaces.image, p);
    ASSERT_FALSE(std::isnan(surface)) << "a receiver point off the windows";  // max() hides NaN
    max_diff = std::max(max_diff, std::abs(QueryAttenuation(full.image, p) - surface));
  }
  std::printf(
      "epsilon %.2f: max |surfaces - full| %.4f; bytes %zu -> %zu; texels walked "
      "%lld -> %lld\n",
      kEpsilon, max_diff, full.bytes.size(), surfaces.bytes.size(),
      static_cast<long long>(full.summary.tasks_stats.texels_walked),
      static_cast<long long>(surfaces.summary.tasks_stats.texels_walked));
  // Each file is within epsilon of the same exact function on receivers.
  EXPECT_LE(max_diff, 2 * kEpsilon);
  EXPECT_LT(surfaces.bytes.size(), full.bytes.size());
  EXPECT_LT(surfaces.summary.tasks_stats.texels_walked, full.summary.tasks_stats.texels_walked);
}

TEST(SurfacesOnly, SameBytesForAnyThreadsAndBatches) {
  TempDir dir;
  const std::string reference = BakePlates(true, 0.01, dir, "a.exr", 1, 0).bytes;
  ASSERT_FALSE(reference.empty());
  EXPECT_EQ(BakePlates(true, 0.01, dir, "b.exr", 2, 5).bytes, reference);
}

TEST(SurfacesOnly, ServiceMatchesTheLocalBakeByteForByte) {
  testing::ServiceCluster cluster(testing::CoordinatorArgs({"--samples-per-task", "8"}));
  ASSERT_TRUE(cluster.StartCoordinator()) << cluster.Log("coordinator.log");
  const std::string scene = testing::WriteServiceScene(cluster.dir(), 64, 16, 32);
  testing::ExpectServiceBakesAsLocal(cluster, scene, 2, "--surfaces-only");
  // `pdsm info` says where the local bake's file is defined (format 2).
  const testing::CommandResult info = testing::RunCommand(
      std::string(PDSM_CLI) + " info " + cluster.dir().File("local.exr") + " --json",
      cluster.dir());
  ASSERT_EQ(info.exit_code, 0) << info.err;
  EXPECT_NE(info.out.find("\"formatVersion\": 2"), std::string::npos) << info.out;
  EXPECT_NE(info.out.find("\"surfacesOnly\": true"), std::string::npos) << info.out;
}

}  // namespace
}  // namespace pdsm
