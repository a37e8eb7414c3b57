#include "core/reference/union_area.h"

#include <gtest/gtest.h>

#include <vector>

#include "core/reference/convex_set.h"
#include "core/reference/polygon_clip.h"

namespace pdsm::internal {
namespace {

using Polygon = std::vector<glm::dvec2>;

constexpr double kTolerance = 1e-10;

Polygon Box(double x0, double y0, double x1, double y1) {
  return {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
}

double Union(const std::vector<Polygon>& polygons) {
  ConvexSet set;
  glm::dvec2 lo(0.0), hi(0.0);
  for (const Polygon& p : polygons) {
    set.Add(p, TwiceSignedArea(p));
    for (const glm::dvec2& q : p) {
      lo = glm::min(lo, q);
      hi = glm::max(hi, q);
    }
  }
  UnionScratch scratch;
  return UnionArea(set, lo, hi, kTolerance, &scratch);
}

TEST(UnionAreaTest, EmptyAndSingle) {
  EXPECT_EQ(Union({}), 0.0);
  EXPECT_DOUBLE_EQ(Union({Box(0, 0, 2, 3)}), 6.0);
}

TEST(UnionAreaTest, OverlapIsCountedOnce) {
  EXPECT_NEAR(Union({Box(0, 0, 2, 2), Box(1, 1, 3, 3)}), 7.0, 1e-12);
  EXPECT_NEAR(Union({Box(0, 0, 4, 4), Box(1, 1, 2, 2)}), 16.0, 1e-12);
}

TEST(UnionAreaTest, SharedEdgeDropsOut) {
  EXPECT_NEAR(Union({Box(0, 0, 1, 1), Box(1, 0, 2, 1)}), 2.0, 1e-12);
}

TEST(UnionAreaTest, IdenticalPolygonsCountOnce) {
  EXPECT_NEAR(Union({Box(0, 0, 1, 1), Box(0, 0, 1, 1), Box(0, 0, 1, 1)}), 1.0, 1e-12);
}

// Two boxes on top of one long one: their edges meet the long edge at a T-junction.
TEST(UnionAreaTest, TJunctionsAreExact) {
  EXPECT_NEAR(Union({Box(0, 0, 2, 1), Box(0, 1, 1, 2), Box(1, 1, 2, 2)}), 4.0, 1e-12);
}

}  // namespace
}  // namespace pdsm::internal
