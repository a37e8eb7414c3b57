#include "client/export/uv_raster.h"

#include <vector>

#include <gtest/gtest.h>

namespace pdsm {
namespace {

// A 4 x 2 world quad (x in [0, 4], z in [0, 2]) over UV [0, 1]^2: u = x / 4, v = z / 2.
struct Quad {
  std::vector<glm::dvec3> points{{0, 0, 0}, {4, 0, 0}, {4, 0, 2}, {0, 0, 2}};
  std::vector<glm::vec2> uvs{{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  std::vector<uint32_t> indices{0, 1, 2, 0, 2, 3};
};

TEST(RasterizeCharts, AFullChartCoversEveryTexelAtItsCentresPoint) {
  const Quad q;
  const ChartRaster r = RasterizeCharts(q.points, q.indices, q.uvs, 8, 4);
  for (int row = 0; row < 4; ++row) {
    for (int column = 0; column < 8; ++column) {
      const size_t i = r.Index(column, row);
      ASSERT_EQ(r.coverage[i], TexelCoverage::kCentre) << column << "," << row;
      EXPECT_NEAR(r.points[i].x, 4 * (column + 0.5) / 8, 1e-12);
      EXPECT_NEAR(r.points[i].z, 2 * (row + 0.5) / 4, 1e-12);
    }
  }
}

TEST(RasterizeCharts, AGrazedTexelTakesTheTrianglesPointNearestItsCentre) {
  // A sliver in texel (0, 0) of an 4 x 4 texture (UV texels are 0.25 wide), not reaching its
  // centre (0.125, 0.125): its nearest point is the vertex at UV (0.1, 0.1).
  const std::vector<glm::dvec3> points{{0, 0, 0}, {10, 0, 0}, {20, 0, 0}};
  const std::vector<glm::vec2> uvs{{0.02f, 0.02f}, {0.1f, 0.02f}, {0.1f, 0.1f}};
  const std::vector<uint32_t> indices{0, 1, 2};
  const ChartRaster r = RasterizeCharts(points, indices, uvs, 4, 4);
  EXPECT_EQ(r.coverage[r.Index(0, 0)], TexelCoverage::kOverlap);
  EXPECT_NEAR(r.points[r.Index(0, 0)].x, 20, 1e-5);
  for (size_t i = 1; i < r.coverage.size(); ++i)
    EXPECT_EQ(r.coverage[i], TexelCoverage::kNone) << i;
}

TEST(RasterizeCharts, TexelsTouchedOnlyAtAnEdgeOrCornerAreNotCovered) {
  // The triangle (0,0), (0.5,0), (0,0.5) of a 4 x 4 texture: its hypotenuse passes through
  // texel corners, so texel (1, 1) touches it at one corner only and (2, 0) at one edge point.
  const std::vector<glm::dvec3> points{{0, 0, 0}, {1, 0, 0}, {0, 0, 1}};
  const std::vector<glm::vec2> uvs{{0, 0}, {0.5f, 0}, {0, 0.5f}};
  const std::vector<uint32_t> indices{0, 1, 2};
  const ChartRaster r = RasterizeCharts(points, indices, uvs, 4, 4);
  EXPECT_EQ(r.coverage[r.Index(0, 0)], TexelCoverage::kCentre);
  // Centres on the hypotenuse itself count as inside (edges are closed).
  EXPECT_EQ(r.coverage[r.Index(1, 0)], TexelCoverage::kCentre);
  EXPECT_EQ(r.coverage[r.Index(0, 1)], TexelCoverage::kCentre);
  EXPECT_EQ(r.coverage[r.Index(1, 1)], TexelCoverage::kNone);
  EXPECT_EQ(r.coverage[r.Index(2, 0)], TexelCoverage::kNone);
  // A slightly smaller triangle leaves those centres outside but still overlaps their texels.
  const std::vector<glm::vec2> smaller{{0, 0}, {0.45f, 0}, {0, 0.45f}};
  const ChartRaster s = RasterizeCharts(points, indices, smaller, 4, 4);
  EXPECT_EQ(s.coverage[s.Index(1, 0)], TexelCoverage::kOverlap);
  EXPECT_EQ(s.coverage[s.Index(0, 1)], TexelCoverage::kOverlap);
  EXPECT_EQ(s.coverage[s.Index(1, 1)], TexelCoverage::kNone);
  EXPECT_EQ(s.coverage[s.Index(2, 0)], TexelCoverage::kNone);
}

TEST(RasterizeCharts, ACentreOnASharedEdgeTakesTheFirstTrianglesPoint) {
  // Two triangles with different world points on each side of the diagonal (a UV seam): the
  // centres on the diagonal belong to the first.
  const std::vector<glm::dvec3> points{{0, 0, 0}, {1, 0, 0}, {1, 0, 1},
                                       {0, 5, 0}, {1, 5, 1}, {0, 5, 1}};
  const std::vector<glm::vec2> uvs{{0, 0}, {1, 0}, {1, 1}, {0, 0}, {1, 1}, {0, 1}};
  const std::vector<uint32_t> indices{0, 1, 2, 3, 4, 5};
  const ChartRaster r = RasterizeCharts(points, indices, uvs, 4, 4);
  for (int k = 0; k < 4; ++k) {
    ASSERT_EQ(r.coverage[r.Index(k, k)], TexelCoverage::kCentre);
    EXPECT_EQ(r.points[r.Index(k, k)].y, 0.0) << k;
  }
  EXPECT_EQ(r.points[r.Index(0, 3)].y, 5.0);
}

TEST(RasterizeCharts, PartsOfChartsOutsideTheUnitSquareAreClipped) {
  const std::vector<glm::dvec3> points{{0, 0, 0}, {1, 0, 0}, {0, 0, 1}};
  const std::vector<glm::vec2> uvs{{-1, -1}, {3, -1}, {-1, 3}};  // covers [0, 1]^2 and more
  const std::vector<uint32_t> indices{0, 1, 2};
  const ChartRaster r = RasterizeCharts(points, indices, uvs, 2, 2);
  for (TexelCoverage c : r.coverage) EXPECT_EQ(c, TexelCoverage::kCentre);
}

TEST(TextureSideFor, GivesTheDensityAskedForOverTheChartsArea) {
  const Quad q;                                                  // world area 8 over UV area 1
  EXPECT_EQ(TextureSideFor(q.points, q.indices, q.uvs, 4), 12);  // ceil(4 sqrt(8)) = 12
  // The same quad over half the UV square per axis: UV area 1/4, twice the texels a side.
  std::vector<glm::vec2> half = q.uvs;
  for (glm::vec2& uv : half) uv *= 0.5f;
  EXPECT_EQ(TextureSideFor(q.points, q.indices, half, 4), 23);  // ceil(8 sqrt(8)) = 23
  std::vector<glm::vec2> flat(4, glm::vec2(0.5f));
  EXPECT_EQ(TextureSideFor(q.points, q.indices, flat, 4), 0);
}

TEST(DilateCharts, GrowsTheCoveredRegionOneRingAPassWithTheNeighboursMean) {
  constexpr int kSide = 7;
  std::vector<float> values(kSide * kSide, 0.0f);
  std::vector<uint8_t> covered(kSide * kSide, 0);
  values[3 * kSide + 3] = 1.0f;  // one covered texel of value 1 in the middle
  covered[3 * kSide + 3] = 1;
  values[0] = 9.0f;  // an uncovered texel's value is not a neighbour's
  DilateCharts(kSide, kSide, 1, 1, &values, &covered);
  int count = 0;
  for (int y = 0; y < kSide; ++y) {
    for (int x = 0; x < kSide; ++x) {
      const bool ring = std::abs(x - 3) <= 1 && std::abs(y - 3) <= 1;
      EXPECT_EQ(covered[y * kSide + x], ring ? 1 : 0) << x << "," << y;
      if (ring) {
        EXPECT_EQ(values[y * kSide + x], 1.0f);
      }
      count += covered[y * kSide + x];
    }
  }
  EXPECT_EQ(count, 9);
  EXPECT_EQ(values[0], 9.0f);
  DilateCharts(kSide, kSide, 1, 5, &values, &covered);  // stops once everything is covered
  for (uint8_t c : covered) EXPECT_EQ(c, 1);
  for (int i = 1; i < kSide * kSide; ++i) EXPECT_EQ(values[i], 1.0f) << i;
}

TEST(DilateCharts, AveragesEachChannelOverTheCoveredNeighbours) {
  // Two channels; texels (0, 0) = (1, 10) and (2, 0) = (3, 30) covered in a 3 x 1 row: the
  // middle one becomes their mean.
  std::vector<float> values{1, 10, 0, 0, 3, 30};
  std::vector<uint8_t> covered{1, 0, 1};
  DilateCharts(3, 1, 2, 1, &values, &covered);
  EXPECT_EQ(values[2], 2.0f);
  EXPECT_EQ(values[3], 20.0f);
  EXPECT_EQ(covered[1], 1);
}

}  // namespace
}  // namespace pdsm
