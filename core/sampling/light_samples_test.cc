#include "core/sampling/light_samples.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

namespace pdsm {
namespace {

bool InUnitSquare(const glm::dvec2& p) {
  return p.x >= 0.0 && p.x < 1.0 && p.y >= 0.0 && p.y < 1.0;
}

const int kCounts[] = {1, 2, 3, 7, 16, 17, 255, 256, 65536};

TEST(StratifiedUnitSquareTest, ExactCountInsideUnitSquare) {
  for (int count : kCounts) {
    const std::vector<glm::dvec2> points = StratifiedUnitSquare(count, 42);
    ASSERT_EQ(points.size(), static_cast<size_t>(count)) << "count " << count;
    for (const glm::dvec2& p : points) {
      ASSERT_TRUE(InUnitSquare(p)) << "count " << count << ": (" << p.x << ", " << p.y << ")";
    }
  }
}

TEST(StratifiedUnitSquareTest, NonPositiveCountGivesNoPoints) {
  EXPECT_TRUE(StratifiedUnitSquare(0, 1).empty());
  EXPECT_TRUE(StratifiedUnitSquare(-3, 1).empty());
}

// The equal-area partition of the contract, rebuilt independently: rows = ceil(sqrt(n)), row r
// holds (n (r+1)) / rows - (n r) / rows cells, its bottom at ((n r) / rows) / n. Each cell must
// hold exactly one point.
TEST(StratifiedUnitSquareTest, OnePointPerEqualAreaCell) {
  for (int count : kCounts) {
    for (uint64_t seed : {1ULL, 7ULL, 0xdeadbeefULL}) {
      const std::vector<glm::dvec2> points = StratifiedUnitSquare(count, seed);
      const int rows = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(count))));
      std::vector<int> first_cell(rows + 1);  // cells before row r
      for (int r = 0; r <= rows; ++r) {
        first_cell[r] = static_cast<int>((static_cast<int64_t>(count) * r) / rows);
      }
      ASSERT_EQ(first_cell[rows], count);
      std::vector<int> hits(count, 0);
      for (const glm::dvec2& p : points) {
        // Row: the last r with bottom <= y.
        int row = rows - 1;
        while (row > 0 && p.y < static_cast<double>(first_cell[row]) / count) --row;
        const int cells = first_cell[row + 1] - first_cell[row];
        ASSERT_GT(cells, 0);
        const int column = std::min(static_cast<int>(std::floor(p.x * cells)), cells - 1);
        ++hits[first_cell[row] + column];
      }
      for (int cell = 0; cell < count; ++cell) {
        ASSERT_EQ(hits[cell], 1) << "count " << count << " seed " << seed << " cell " << cell;
      }
    }
  }
}

// The row heights follow the cell counts, so every cell has area 1 / n.
TEST(StratifiedUnitSquareTest, CellsHaveEqualArea) {
  for (int count : kCounts) {
    const int rows = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(count))));
    for (int r = 0; r < rows; ++r) {
      const int64_t cells = (int64_t{count} * (r + 1)) / rows - (int64_t{count} * r) / rows;
      const double height = static_cast<double>(cells) / count;
      EXPECT_NEAR(height / static_cast<double>(cells), 1.0 / count, 1e-15);
    }
  }
}

TEST(StratifiedUnitSquareTest, DeterministicPerSeed) {
  const auto a = StratifiedUnitSquare(257, 99);
  const auto b = StratifiedUnitSquare(257, 99);
  const auto c = StratifiedUnitSquare(257, 100);
  EXPECT_EQ(a, b);
  ASSERT_EQ(a.size(), c.size());
  EXPECT_NE(a, c);
}

TEST(UniformUnitSquareTest, CountRangeAndDeterminism) {
  for (int count : kCounts) {
    const auto points = UniformUnitSquare(count, 5);
    ASSERT_EQ(points.size(), static_cast<size_t>(count));
    for (const glm::dvec2& p : points) ASSERT_TRUE(InUnitSquare(p));
  }
  EXPECT_EQ(UniformUnitSquare(100, 3), UniformUnitSquare(100, 3));
  EXPECT_NE(UniformUnitSquare(100, 3), UniformUnitSquare(100, 4));
}

TEST(UniformUnitSquareTest, MeanIsCentre) {
  const auto points = UniformUnitSquare(65536, 11);
  glm::dvec2 sum(0.0);
  for (const glm::dvec2& p : points) sum += p;
  const glm::dvec2 mean = sum / static_cast<double>(points.size());
  // Standard error of the mean: sqrt(1/12 / 65536) ~ 0.0011.
  EXPECT_NEAR(mean.x, 0.5, 0.006);
  EXPECT_NEAR(mean.y, 0.5, 0.006);
}

TEST(ConcentricDiskTest, MapsIntoUnitDisk) {
  constexpr int kGrid = 400;
  for (int i = 0; i <= kGrid; ++i) {
    for (int j = 0; j <= kGrid; ++j) {
      const glm::dvec2 u(static_cast<double>(i) / kGrid, static_cast<double>(j) / kGrid);
      const glm::dvec2 d = ConcentricDisk(u);
      ASSERT_LE(glm::length(d), 1.0 + 1e-12) << u.x << ", " << u.y;
    }
  }
  EXPECT_EQ(ConcentricDisk({0.5, 0.5}), glm::dvec2(0.0, 0.0));
  // The square's edge midpoints land on the circle.
  EXPECT_NEAR(glm::length(ConcentricDisk({1.0, 0.5})), 1.0, 1e-12);
  EXPECT_NEAR(glm::length(ConcentricDisk({0.5, 0.0})), 1.0, 1e-12);
}

// Area preservation: the fraction of a uniform grid of inputs landing in a region equals the
// region's share of the disk.
TEST(ConcentricDiskTest, PreservesAreaFractions) {
  constexpr int kGrid = 1000;
  int inner = 0, quadrant[4] = {0, 0, 0, 0}, ring = 0;
  for (int i = 0; i < kGrid; ++i) {
    for (int j = 0; j < kGrid; ++j) {
      const glm::dvec2 d = ConcentricDisk({(i + 0.5) / kGrid, (j + 0.5) / kGrid});
      const double r = glm::length(d);
      if (r < 0.5) ++inner;
      if (r >= 0.9) ++ring;
      ++quadrant[(d.x >= 0 ? 0 : 1) + (d.y >= 0 ? 0 : 2)];
    }
  }
  const double total = static_cast<double>(kGrid) * kGrid;
  EXPECT_NEAR(inner / total, 0.25, 0.01 * 0.25);
  EXPECT_NEAR(ring / total, 1.0 - 0.81, 0.01 * 0.19);
  for (int q = 0; q < 4; ++q) EXPECT_NEAR(quadrant[q] / total, 0.25, 0.0025) << "quadrant " << q;
}

LightSpec RectLight(double half_width, double half_height) {
  LightSpec light;
  light.shape = LightShape::kRect;
  light.half_width = half_width;
  light.half_height = half_height;
  return light;
}

TEST(GenerateLightSamplesTest, RectSamplesWithinHalfSizesAndCentred) {
  const LightSpec light = RectLight(1.5, 0.25);
  for (SamplingPattern pattern :
       {SamplingPattern::kStratified, SamplingPattern::kUniform, SamplingPattern::kSobol,
        SamplingPattern::kHalton, SamplingPattern::kBlueNoise}) {
    const auto samples = GenerateLightSamples(light, 4096, pattern, 3);
    ASSERT_EQ(samples.size(), 4096u);
    glm::dvec2 sum(0.0);
    glm::dvec2 lo(1e9), hi(-1e9);
    for (const glm::dvec2& p : samples) {
      ASSERT_LE(std::abs(p.x), 1.5);
      ASSERT_LE(std::abs(p.y), 0.25);
      sum += p;
      lo = glm::min(lo, p);
      hi = glm::max(hi, p);
    }
    const glm::dvec2 mean = sum / 4096.0;
    EXPECT_NEAR(mean.x, 0.0, 0.03 * 1.5);
    EXPECT_NEAR(mean.y, 0.0, 0.03 * 0.25);
    // The samples spread over the whole light, not a part of it.
    EXPECT_LT(lo.x, -1.4);
    EXPECT_GT(hi.x, 1.4);
    EXPECT_LT(lo.y, -0.23);
    EXPECT_GT(hi.y, 0.23);
  }
}

TEST(GenerateLightSamplesTest, StratifiedRectMeanIsTight) {
  // Stratification pins the mean far closer than independent samples would.
  const auto samples =
      GenerateLightSamples(RectLight(1.0, 1.0), 1024, SamplingPattern::kStratified, 8);
  glm::dvec2 sum(0.0);
  for (const glm::dvec2& p : samples) sum += p;
  EXPECT_NEAR(sum.x / 1024, 0.0, 0.005);
  EXPECT_NEAR(sum.y / 1024, 0.0, 0.005);
}

TEST(GenerateLightSamplesTest, DiskSamplesWithinRadius) {
  LightSpec light;
  light.shape = LightShape::kDisk;
  light.radius = 2.5;
  const auto samples = GenerateLightSamples(light, 4096, SamplingPattern::kStratified, 17);
  ASSERT_EQ(samples.size(), 4096u);
  double max_r = 0;
  glm::dvec2 sum(0.0);
  for (const glm::dvec2& p : samples) {
    ASSERT_LE(glm::length(p), 2.5 * (1 + 1e-12));
    max_r = std::max(max_r, glm::length(p));
    sum += p;
  }
  EXPECT_GT(max_r, 2.4);
  EXPECT_NEAR(sum.x / 4096, 0.0, 0.05);
  EXPECT_NEAR(sum.y / 4096, 0.0, 0.05);
}

TEST(GenerateLightSamplesTest, SunSamplesWithinAngle) {
  LightSpec light;
  light.shape = LightShape::kSun;
  light.tan_half_angle = std::tan(0.3 * std::numbers::pi / 180.0);
  const auto samples = GenerateLightSamples(light, 1000, SamplingPattern::kUniform, 23);
  ASSERT_EQ(samples.size(), 1000u);
  double max_r = 0;
  for (const glm::dvec2& p : samples) {
    ASSERT_LE(glm::length(p), light.tan_half_angle * (1 + 1e-12));
    max_r = std::max(max_r, glm::length(p));
  }
  EXPECT_GT(max_r, 0.9 * light.tan_half_angle);
}

TEST(GenerateLightSamplesTest, DeterministicInAllInputs) {
  const LightSpec light = RectLight(1.0, 2.0);
  const auto a = GenerateLightSamples(light, 64, SamplingPattern::kStratified, 1);
  EXPECT_EQ(a, GenerateLightSamples(light, 64, SamplingPattern::kStratified, 1));
  EXPECT_NE(a, GenerateLightSamples(light, 64, SamplingPattern::kStratified, 2));
  EXPECT_NE(a, GenerateLightSamples(light, 64, SamplingPattern::kUniform, 1));
}

}  // namespace
}  // namespace pdsm
