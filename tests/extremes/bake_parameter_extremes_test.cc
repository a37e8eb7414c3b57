// Extremes of the bake parameters: sample counts 1, 2, 7 and 65536; epsilon 0, 1e-6 and 1;
// PDSM resolutions 1 x 1, 1000 x 3 with tile sizes that do not divide them, and 1 x 65536
// (the longest side a map may have).
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "core/pdsm/attenuation_function.h"
#include "tests/extremes/extremes_support.h"

namespace pdsm::extremes {
namespace {

// The world point where pixel (i, j)'s ray meets the plane y = height (light overhead).
glm::dvec3 PixelRayOnPlane(const PdsmImage& image, int i, int j, double height) {
  const PdsmGeometry& g = image.header.geometry;
  const double s = g.PixelCenterS(i), t = g.PixelCenterT(j);
  // Light at y = 5 facing down: light-space depth of the plane is 5 - height.
  const double z = 5.0 - height;
  return g.frame.WorldFromLight({s * z, t * z, z});
}

struct PixelErrors {
  double mean = 0;
  double max_off_grid = 0;  // largest distance of A * N from an integer
};

// Each pixel's own function (no blending) at its ray's ground point against the exact value.
PixelErrors PixelCentreErrors(const PdsmImage& image, const Scene& scene) {
  const PdsmGeometry& g = image.header.geometry;
  std::vector<glm::dvec3> points;
  std::vector<double> baked;
  PixelErrors e;
  for (int j = 0; j < g.height; ++j) {
    for (int i = 0; i < g.width; ++i) {
      points.push_back(PixelRayOnPlane(image, i, j, 0.0));
      const double a = EvaluateAttenuation(image.Function(i, j), 5.0);
      baked.push_back(a);
      const double n = a * image.header.samples;
      e.max_off_grid = std::max(e.max_off_grid, std::abs(n - std::round(n)));
    }
  }
  absl::StatusOr<std::vector<double>> exact = ExactAttenuation(scene, points);
  EXPECT_TRUE(exact.ok());
  if (!exact.ok()) return e;
  for (size_t k = 0; k < points.size(); ++k) e.mean += std::abs(baked[k] - (*exact)[k]);
  e.mean /= static_cast<double>(points.size());
  return e;
}

class ExtremesSamples : public ::testing::TestWithParam<int> {};

// With epsilon 0 every stored value is a multiple of 1/N, and the error against the exact
// attenuation falls with N: 65536 samples leave only the shadow maps' resolution.
TEST_P(ExtremesSamples, ValuesAreMultiplesOfOneOverNAndErrorFalls) {
  const int n = GetParam();
  Scene scene = PlateScene();
  scene.bake.width = scene.bake.height = 16;
  scene.bake.samples = n;
  scene.bake.shadow_map_resolution = 128;
  pdsm::testing::TempDir dir;
  LocalBakeOptions options;
  options.output_path = dir.File("out.exr");
  options.threads = 2;
  options.samples_per_task = n > 4096 ? 4096 : 0;
  absl::StatusOr<BakeSummary> summary = RunLocalBake(scene, options);
  ASSERT_TRUE(summary.ok()) << summary.status();
  absl::StatusOr<PdsmImage> image = ReadPdsm(options.output_path);
  ASSERT_TRUE(image.ok());
  EXPECT_EQ(image->header.samples, n);
  const PixelErrors e = PixelCentreErrors(*image, scene);
  std::printf("samples %d: mean error %.4f, off-grid %.2e\n", n, e.mean, e.max_off_grid);
  EXPECT_LT(e.max_off_grid, 1e-3);
  // Measured: 1 -> 0.088, 2 -> 0.047, 7 -> 0.030, 65536 -> 0.0034.
  const double bound = n == 1 ? 0.2 : n == 2 ? 0.12 : n == 7 ? 0.06 : 0.01;
  EXPECT_LT(e.mean, bound);
}

INSTANTIATE_TEST_SUITE_P(Counts, ExtremesSamples, ::testing::Values(1, 2, 7, 65536));

// Compressing with epsilon moves no answer by more than epsilon from the lossless file, at
// every depth of every pixel; epsilon 1 leaves a few vertices per pixel.
TEST(ExtremesEpsilon, ZeroOneMillionthAndOne) {
  Scene scene = PlateScene(2.0);
  scene.bake.samples = 64;
  const std::optional<Baked> lossless = Bake(scene);
  ASSERT_TRUE(lossless);
  const PdsmGeometry& g = lossless->image.header.geometry;
  for (const double epsilon : {1e-6, 1.0}) {
    scene.bake.epsilon = epsilon;
    const std::optional<Baked> lossy = Bake(scene);
    ASSERT_TRUE(lossy);
    double max_diff = 0;
    int nonempty = 0;
    for (int j = 0; j < g.height; ++j) {
      for (int i = 0; i < g.width; ++i) {
        const auto exact = lossless->image.Function(i, j);
        const auto stored = lossy->image.Function(i, j);
        nonempty += !exact.empty();
        std::vector<double> depths;
        for (const Vertex& v : exact) depths.push_back(v.z);
        for (int k = 0; k <= 64; ++k) depths.push_back(g.z_near + (g.z_far - g.z_near) * k / 50.0);
        for (double z : depths) {
          max_diff =
              std::max(max_diff, std::abs(static_cast<double>(EvaluateAttenuation(stored, z)) -
                                          EvaluateAttenuation(exact, z)));
        }
      }
    }
    std::printf("epsilon %g: %zu vertices (lossless %zu), max |A' - A| %.3g\n", epsilon,
                lossy->image.vertices.size(), lossless->image.vertices.size(), max_diff);
    EXPECT_LE(max_diff, epsilon);
    if (epsilon == 1.0) {
      // Only jumps of the whole light (0 to 1 at one depth) survive epsilon = 1.
      EXPECT_LT(lossy->image.vertices.size(), lossless->image.vertices.size() / 10);
      EXPECT_LE(lossy->image.vertices.size(), 4u * nonempty);
    } else {
      EXPECT_LE(lossy->image.vertices.size(), lossless->image.vertices.size());
    }
  }
  EXPECT_GT(lossless->image.vertices.size(), 0u);
}

// 1 x 1 with tiles of 64: one partial tile. Its one pixel's ray at the ground matches the
// exact value there.
TEST(ExtremesResolution, OneByOne) {
  Scene scene = PlateScene();
  scene.bake.width = scene.bake.height = 1;
  scene.bake.tile_size = 64;
  const std::optional<Baked> baked = Bake(scene);
  ASSERT_TRUE(baked);
  EXPECT_EQ(baked->image.header.geometry.width, 1);
  EXPECT_EQ(baked->image.header.geometry.height, 1);
  const PixelErrors e = PixelCentreErrors(baked->image, scene);
  std::printf("1x1: error %.4f\n", e.mean);
  EXPECT_LT(e.mean, 0.05);
}

// 1000 x 3 with tiles of 7: 143 x 1 tiles, the last column 6 wide, every row partial.
TEST(ExtremesResolution, ThousandByThreeWithTilesOfSeven) {
  Scene scene = PlateScene();
  scene.bake.width = 1000;
  scene.bake.height = 3;
  scene.bake.tile_size = 7;
  scene.bake.samples = 16;
  const std::optional<Baked> baked = Bake(scene);
  ASSERT_TRUE(baked);
  EXPECT_EQ(baked->summary.tiles, 143);
  EXPECT_EQ(baked->image.header.geometry.width, 1000);
  EXPECT_EQ(baked->image.header.geometry.height, 3);
  const PixelErrors e = PixelCentreErrors(baked->image, scene);
  std::printf("1000x3: mean error %.4f\n", e.mean);
  EXPECT_LT(e.mean, 0.03);
  EXPECT_LT(e.max_off_grid, 1e-3);
}

// 1 x 65536 (the scene format's longest side) in tiles of 64: a column of 1024 tiles, each one
// pixel wide, whose pixels are 1 / 65536 of the window tall: every pixel's function at its
// ground point against the exact value.
TEST(ExtremesResolution, OneBy65536) {
  Scene scene = PlateScene();
  scene.bake.width = 1;
  scene.bake.height = kMaxPdsmResolution;
  scene.bake.tile_size = 64;
  scene.bake.samples = 16;
  const std::optional<Baked> baked = Bake(scene);
  ASSERT_TRUE(baked);
  EXPECT_EQ(baked->summary.tiles, 1024);
  EXPECT_EQ(baked->image.header.geometry.width, 1);
  EXPECT_EQ(baked->image.header.geometry.height, 65536);
  const PixelErrors e = PixelCentreErrors(baked->image, scene);
  std::printf("1x65536: mean error %.4f\n", e.mean);
  EXPECT_LT(e.mean, 0.03);
  EXPECT_LT(e.max_off_grid, 1e-3);
}

}  // namespace
}  // namespace pdsm::extremes
