// Light samples: one per equal-area cell for any count, deterministic, inside the light.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "core/sampling/light_samples.h"

namespace pdsm {
namespace {

// Index of the equal-area cell holding p (see StratifiedUnitSquare).
int CellOf(const glm::dvec2& p, int count) {
  const int rows = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(count))));
  double bottom = 0.0;
  int first = 0;
  for (int r = 0; r < rows; ++r) {
    const int cells = (count * (r + 1)) / rows - (count * r) / rows;
    const double top = bottom + static_cast<double>(cells) / count;
    if (p.y < top || r == rows - 1) return first + static_cast<int>(p.x * cells);
    bottom = top;
    first += cells;
  }
  return -1;
}

TEST(Stratification, OneSamplePerEqualAreaCell) {
  for (int count : {1, 2, 3, 7, 16, 17, 255, 256, 65536}) {
    const std::vector<glm::dvec2> points = StratifiedUnitSquare(count, 42);
    ASSERT_EQ(static_cast<int>(points.size()), count);
    std::vector<int> hits(count, 0);
    for (const glm::dvec2& p : points) {
      ASSERT_GE(p.x, 0.0);
      ASSERT_LT(p.x, 1.0);
      ASSERT_GE(p.y, 0.0);
      ASSERT_LT(p.y, 1.0);
      const int cell = CellOf(p, count);
      ASSERT_GE(cell, 0);
      ASSERT_LT(cell, count);
      ++hits[cell];
    }
    for (int h : hits) ASSERT_EQ(h, 1) << "count " << count;
  }
}

TEST(Stratification, DeterministicPerSeed) {
  EXPECT_EQ(StratifiedUnitSquare(64, 1), StratifiedUnitSquare(64, 1));
  EXPECT_NE(StratifiedUnitSquare(64, 1), StratifiedUnitSquare(64, 2));
}

TEST(Stratification, LightShapesStayInside) {
  LightSpec rect;
  rect.shape = LightShape::kRect;
  rect.half_width = 2;
  rect.half_height = 0.5;
  glm::dvec2 mean(0.0);
  for (const glm::dvec2& p : GenerateLightSamples(rect, 1024, SamplingPattern::kStratified, 3)) {
    ASSERT_LE(std::abs(p.x), 2.0);
    ASSERT_LE(std::abs(p.y), 0.5);
    mean += p / 1024.0;
  }
  EXPECT_NEAR(mean.x, 0.0, 0.01);
  EXPECT_NEAR(mean.y, 0.0, 0.01);
  LightSpec disk;
  disk.shape = LightShape::kDisk;
  disk.radius = 3;
  int inner = 0;
  for (const glm::dvec2& p : GenerateLightSamples(disk, 4096, SamplingPattern::kStratified, 3)) {
    ASSERT_LE(glm::length(p), 3.0 + 1e-12);
    inner += glm::length(p) < 1.5;
  }
  EXPECT_NEAR(inner / 4096.0, 0.25, 0.01);  // the concentric map preserves area
}

}  // namespace
}  // namespace pdsm
