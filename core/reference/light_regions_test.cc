#include "core/reference/light_regions.h"

#include <gtest/gtest.h>

#include <optional>
#include <vector>

namespace pdsm::internal {
namespace {

using Polygon = std::vector<glm::dvec2>;

TEST(PrepareLightTest, NonConvexLightRegionsTileIt) {
  // An L of area 3, clockwise: prepared counter-clockwise, cut into triangles.
  const Polygon l_shape = {{0, 0}, {0, 2}, {1, 2}, {1, 1}, {2, 1}, {2, 0}};
  const std::optional<PreparedLight> light = PrepareLight(l_shape);
  ASSERT_TRUE(light.has_value());
  EXPECT_DOUBLE_EQ(light->area, 3.0);
  ASSERT_GT(light->regions.size(), 1u);
  double sum = 0.0;
  for (const Region& region : light->regions) {
    EXPECT_GT(region.area, 0.0);
    sum += region.area;
  }
  EXPECT_NEAR(sum, 3.0, 1e-12);
}

TEST(PrepareLightTest, DegenerateLightIsNullopt) {
  EXPECT_FALSE(PrepareLight(Polygon{{0, 0}, {1, 1}, {2, 2}}).has_value());
  EXPECT_FALSE(PrepareLight(Polygon{{0, 0}, {1, 0}}).has_value());
}

}  // namespace
}  // namespace pdsm::internal
