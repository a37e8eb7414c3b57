// End-to-end accuracy: bake a scene, read the file back, and compare `pdsm query`'s
// attenuation with the exact polygon-projection reference (core/reference), on receiver
// surfaces and in free space. Tolerances are stated in docs/accuracy.md.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "core/pdsm/pdsm_file.h"
#include "core/pdsm/pdsm_query.h"
#include "core/reference/accuracy_points.h"
#include "core/reference/exact_visibility.h"
#include "core/scene/scene_loader.h"
#include "tests/box_on_plane.h"
#include "tests/test_support.h"
#include "worker/local_bake.h"

namespace pdsm {
namespace {

using testing::ExamplePath;
using testing::TempDir;

ErrorStats Compare(const PdsmImage& pdsm, const Scene& scene,
                   const std::vector<glm::dvec3>& points) {
  absl::StatusOr<std::vector<double>> exact = ExactAttenuation(scene, points);
  EXPECT_TRUE(exact.ok()) << exact.status();
  std::vector<double> baked(points.size());
  for (size_t k = 0; k < points.size(); ++k) {
    baked[k] = QueryAttenuation(pdsm, points[k]);
    EXPECT_FALSE(std::isnan(baked[k])) << "point " << k << " outside the PDSM";
  }
  // NaN on either side is left out (the expectation above reports it).
  return exact.ok() ? CompareAttenuation(baked, *exact) : ErrorStats{};
}

std::vector<glm::dvec3> GroundGrid(double half, int n, double y) {
  std::vector<glm::dvec3> points;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      points.emplace_back(-half + 2 * half * (i + 0.5) / n, y, -half + 2 * half * (j + 0.5) / n);
    }
  }
  return points;
}

std::vector<glm::dvec3> RandomBox(glm::dvec3 lo, glm::dvec3 hi, int n, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<glm::dvec3> points;
  for (int k = 0; k < n; ++k) {
    points.push_back(lo + glm::dvec3(u(rng), u(rng), u(rng)) * (hi - lo));
  }
  return points;
}

// Bakes `scene` into `path` with the local bake and reads it back whole.
PdsmImage* BakeAndRead(const Scene& scene, const std::string& path) {
  LocalBakeOptions options;
  options.output_path = path;
  absl::StatusOr<BakeSummary> summary = RunLocalBake(scene, options);
  EXPECT_TRUE(summary.ok()) << summary.status();
  absl::StatusOr<PdsmImage> pdsm = ReadPdsm(path);
  EXPECT_TRUE(pdsm.ok()) << pdsm.status();
  return summary.ok() && pdsm.ok() ? new PdsmImage(*std::move(pdsm)) : nullptr;
}

class PlatesAccuracy : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    pdsm::v1::BakeParams overrides;
    overrides.add_resolution(256);
    overrides.add_resolution(256);
    overrides.set_samples(256);
    overrides.set_shadow_map_resolution(1024);
    overrides.set_epsilon(0.005);
    auto scene = LoadSceneFile(ExamplePath("plates"), overrides);
    ASSERT_TRUE(scene.ok()) << scene.status();
    scene_ = new Scene(*std::move(scene));
    dir_ = new TempDir();
    pdsm_ = BakeAndRead(*scene_, dir_->File("plates.exr"));
  }
  static void TearDownTestSuite() {
    delete pdsm_;
    delete scene_;
    delete dir_;
  }
  static Scene* scene_;
  static PdsmImage* pdsm_;
  static TempDir* dir_;
};
Scene* PlatesAccuracy::scene_ = nullptr;
PdsmImage* PlatesAccuracy::pdsm_ = nullptr;
TempDir* PlatesAccuracy::dir_ = nullptr;

TEST_F(PlatesAccuracy, GroundReceiverMatchesExactReference) {
  ASSERT_NE(pdsm_, nullptr);
  const ErrorStats e = Compare(*pdsm_, *scene_, GroundGrid(6.0, 40, 0.0));
  RecordProperty("mean_abs_error", std::to_string(e.mean));
  std::printf("ground: n=%zu mean %.4f p95 %.4f max %.4f\n", e.count, e.mean, e.p95, e.max);
  EXPECT_EQ(e.count, 1600u);
  // Measured: mean 0.0021, p95 0.011 (docs/accuracy.md).
  EXPECT_LT(e.mean, 0.005);
  EXPECT_LT(e.p95, 0.025);
}

TEST_F(PlatesAccuracy, FreeSpacePointsMatchExactReference) {
  ASSERT_NE(pdsm_, nullptr);
  const ErrorStats e = Compare(*pdsm_, *scene_, RandomBox({-5, 0.05, -5}, {5, 3.9, 5}, 1500, 7));
  std::printf("volume: n=%zu mean %.4f p95 %.4f max %.4f\n", e.count, e.mean, e.p95, e.max);
  EXPECT_EQ(e.count, 1500u);
  // Measured: mean 0.0018, p95 0.0088.
  EXPECT_LT(e.mean, 0.005);
  EXPECT_LT(e.p95, 0.02);
}

// Issue #15: compression keeps exact plateaus, so a point whose neighbourhood is all umbra reads
// exactly 1 and one whose neighbourhood is all lit exactly 0 (before, the umbra read 0.9965 on
// average: epsilon lifted it). The neighbourhood (the point and 0.25 units around it, more than
// two PDSM pixels) is what the bilinear lookup blends.
TEST_F(PlatesAccuracy, UmbraReadsExactlyOneAndLitGroundExactlyZero) {
  ASSERT_NE(pdsm_, nullptr);
  const std::vector<glm::dvec3> grid = GroundGrid(6.0, 120, 0.0);
  const glm::dvec3 offsets[] = {
      {0, 0, 0}, {0.25, 0, 0}, {-0.25, 0, 0}, {0, 0, 0.25}, {0, 0, -0.25}};
  std::vector<glm::dvec3> probes;
  for (const glm::dvec3& p : grid) {
    for (const glm::dvec3& o : offsets) probes.push_back(p + o);
  }
  absl::StatusOr<std::vector<double>> exact = ExactAttenuation(*scene_, probes);
  ASSERT_TRUE(exact.ok()) << exact.status();
  int umbra = 0, lit = 0;
  for (size_t k = 0; k < grid.size(); ++k) {
    const auto around = exact->begin() + static_cast<ptrdiff_t>(k * std::size(offsets));
    const bool all_umbra =
        std::all_of(around, around + std::size(offsets), [](double a) { return a == 1.0; });
    const bool all_lit =
        std::all_of(around, around + std::size(offsets), [](double a) { return a == 0.0; });
    if (!all_umbra && !all_lit) continue;
    const double baked = QueryAttenuation(*pdsm_, grid[k]);
    if (all_umbra) {
      ++umbra;
      EXPECT_EQ(baked, 1.0) << "umbra point " << grid[k].x << ", " << grid[k].z;
    } else {
      ++lit;
      EXPECT_EQ(baked, 0.0) << "lit point " << grid[k].x << ", " << grid[k].z;
    }
  }
  std::printf("exact plateaus: %d umbra points, %d lit points\n", umbra, lit);
  EXPECT_GE(umbra, 20);  // 25: the casters are small under a large light, its umbra too
  EXPECT_GE(lit, 4000);  // 7357
}

TEST_F(PlatesAccuracy, CasterSurfacesDoNotShadowThemselves) {
  ASSERT_NE(pdsm_, nullptr);
  // The top of the triangle plate at y = 2 (light above): lit except under the upper plate.
  std::vector<glm::dvec3> points;
  for (int k = 0; k < 200; ++k) {
    const double u = (k % 20 + 0.5) / 20.0, v = (k / 20 + 0.5) / 10.0;
    // Inside the triangle (0.5,2,0.5), (2.5,2,0.5), (1.5,2,2.3): barycentric fill.
    const double x = 0.5 + 2.0 * u * (1 - v) + v * 1.0;
    const double z = 0.5 + 1.8 * v;
    points.emplace_back(x, 2.0, z);
  }
  const ErrorStats e = Compare(*pdsm_, *scene_, points);
  std::printf("caster top: n=%zu mean %.4f p95 %.4f max %.4f\n", e.count, e.mean, e.p95, e.max);
  // Without the bias the plate would hide itself (attenuation 1); measured max 0.
  EXPECT_LT(e.max, 0.02);
}

// Issue #15 item 3, contact shadows. A unit box rests on the ground; a small rect light stands
// 3.5 units to its -x side, 4 up. On the +x side the box's umbra starts at the wall: the
// ground there is hidden from every light point right up to the contact, and must read so (a
// depth bias that let light in under the wall would show here). On the -x side the ground is
// lit right up to the wall and must read exactly 0 there: no smear of the box's shadow onto
// the visible ground. What is not exact is inside the solid: ground under the box within one
// PDSM pixel of the lit wall blends with the lit ray beside it (and lies within the depth
// bias behind the wall), so it reads less than 1 although nothing can see it. That is where
// the dragon's contact errors of issue #15 sit (docs/accuracy.md, "Contact shadows").
class ContactAccuracy : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir();
    const std::string scene_path = dir_->File("box_on_plane.json");
    testing::WriteText(scene_path, testing::kBoxOnPlaneJson);
    auto scene = LoadSceneFile(scene_path);
    ASSERT_TRUE(scene.ok()) << scene.status();
    scene_ = new Scene(*std::move(scene));
    pdsm_ = BakeAndRead(*scene_, dir_->File("box_on_plane.exr"));
  }
  static void TearDownTestSuite() {
    delete pdsm_;
    delete scene_;
    delete dir_;
  }
  // The PDSM pixel's size on the ground at `p`.
  static double GroundPixel(const glm::dvec3& p) {
    return testing::BoxGroundPixel(pdsm_->header.geometry, p);
  }
  static Scene* scene_;
  static PdsmImage* pdsm_;
  static TempDir* dir_;
};
Scene* ContactAccuracy::scene_ = nullptr;
PdsmImage* ContactAccuracy::pdsm_ = nullptr;
TempDir* ContactAccuracy::dir_ = nullptr;

TEST_F(ContactAccuracy, UmbraReachesTheContactOnTheShadowSide) {
  ASSERT_NE(pdsm_, nullptr);
  for (double d : {0.002, 0.005, 0.01, 0.02, 0.05, 0.1, 0.2, 0.4}) {
    const std::vector<glm::dvec3> points = testing::AlongBoxWall(+1, d);
    absl::StatusOr<std::vector<double>> exact = ExactAttenuation(*scene_, points);
    ASSERT_TRUE(exact.ok()) << exact.status();
    for (size_t k = 0; k < points.size(); ++k) {
      ASSERT_GT((*exact)[k], 1 - 1e-9) << "the premise: umbra at " << d << " from the wall";
      EXPECT_GE(QueryAttenuation(*pdsm_, points[k]), 0.95)
          << "ground " << d << " from the wall, z " << points[k].z;
    }
  }
}

TEST_F(ContactAccuracy, LitGroundStaysLitUpToTheWall) {
  ASSERT_NE(pdsm_, nullptr);
  const double pixel = GroundPixel({-0.5, 0, 0});
  ASSERT_GT(pixel, 0.01);  // 0.031 here
  for (double d : {0.002, 0.1, 0.25, 0.5, 1.0, 2.0, 5.0}) {
    const std::vector<glm::dvec3> points = testing::AlongBoxWall(-1, d * pixel);
    absl::StatusOr<std::vector<double>> exact = ExactAttenuation(*scene_, points);
    ASSERT_TRUE(exact.ok()) << exact.status();
    for (size_t k = 0; k < points.size(); ++k) {
      ASSERT_EQ((*exact)[k], 0.0) << "the premise: lit at " << d << " pixels from the wall";
      EXPECT_EQ(QueryAttenuation(*pdsm_, points[k]), 0.0)
          << "ground " << d << " pixels from the wall, z " << points[k].z;
    }
  }
}

TEST_F(ContactAccuracy, UnderTheBoxIsHiddenBeyondOnePixelOfTheLitWall) {
  ASSERT_NE(pdsm_, nullptr);
  const double pixel = GroundPixel({-0.5, 0, 0});
  double least_within = 1;
  for (double d : {0.25, 0.5, 0.75, 1.5, 2.0, 4.0, 8.0}) {
    // Inside the footprint, d pixels from the lit wall (negative distance outside it).
    const std::vector<glm::dvec3> points = testing::AlongBoxWall(-1, -d * pixel);
    for (const glm::dvec3& p : points) {
      const double baked = QueryAttenuation(*pdsm_, p);
      if (d > 1.0) {
        EXPECT_GE(baked, 0.95) << "under the box, " << d << " pixels from the lit wall";
      } else {
        least_within = std::min(least_within, baked);
      }
    }
  }
  // Measured (pdsm query): 0 a third of a pixel in, 0.17 at two thirds, 0.49 at one. Nothing sees
  // these points (they are inside the box); the adaptive resolution of issue #15 item 2 narrows it.
  std::printf("under the box within one pixel (%.4f) of the lit wall: down to %.3f\n", pixel,
              least_within);
}

}  // namespace
}  // namespace pdsm
