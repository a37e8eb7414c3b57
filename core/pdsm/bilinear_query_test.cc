// Queries: projection into the PDSM and bilinear blending of the four neighbours' results.
#include <cmath>

#include <gtest/gtest.h>

#include "core/pdsm/pdsm_query.h"

namespace pdsm {
namespace {

// A 2x2 PDSM over the window [-1, 1]^2, light at the origin looking along +z; pixel (i, j)
// is hidden by value[j][i] beyond depth 1.
PdsmImage TwoByTwo(const float value[2][2]) {
  PdsmImage image;
  PdsmGeometry& g = image.header.geometry;
  g.width = g.height = 2;
  g.s_min = g.t_min = -1;
  g.s_max = g.t_max = 1;
  image.offsets.push_back(0);
  for (int j = 0; j < 2; ++j) {
    for (int i = 0; i < 2; ++i) {
      image.vertices.push_back({1.0f, 0.0f});
      image.vertices.push_back({1.0f, value[j][i]});
      image.offsets.push_back(image.vertices.size());
    }
  }
  return image;
}

TEST(BilinearQuery, BlendsResultsOfFourPixels) {
  const float value[2][2] = {{0.0f, 1.0f}, {0.5f, 0.25f}};
  const PdsmImage image = TwoByTwo(value);
  // Pixel centres are at s, t = +-0.5 (times z for the perspective projection).
  EXPECT_NEAR(QueryAttenuation(image, {-0.5 * 2, -0.5 * 2, 2}), 0.0, 1e-7);
  EXPECT_NEAR(QueryAttenuation(image, {0.5 * 2, -0.5 * 2, 2}), 1.0, 1e-7);
  EXPECT_NEAR(QueryAttenuation(image, {0.0, -0.5 * 2, 2}), 0.5, 1e-7);
  EXPECT_NEAR(QueryAttenuation(image, {0.0, 0.0, 2}), (0.0 + 1.0 + 0.5 + 0.25) / 4, 1e-7);
  EXPECT_NEAR(QueryAttenuation(image, {0.25 * 2, 0.0, 2}), 0.5 * (0.75 * 1.0 + 0.25 * 0.0) +
                                                                0.5 * (0.75 * 0.25 + 0.25 * 0.5),
              1e-7);
  // Beyond the border pixel centres the edge clamps.
  EXPECT_NEAR(QueryAttenuation(image, {-0.9 * 2, -0.9 * 2, 2}), 0.0, 1e-7);
  // In front of the step: lit.
  EXPECT_EQ(QueryAttenuation(image, {0.0, 0.0, 0.5}), 0.0);
}

TEST(BilinearQuery, OutsideTheFrustumIsNan) {
  const float value[2][2] = {{1, 1}, {1, 1}};
  const PdsmImage image = TwoByTwo(value);
  EXPECT_TRUE(std::isnan(QueryAttenuation(image, {0, 0, -1})));   // behind the light
  EXPECT_TRUE(std::isnan(QueryAttenuation(image, {5, 0, 2})));    // s = 2.5 > 1
}

}  // namespace
}  // namespace pdsm
