#include "core/pdsm/pdsm_query.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <span>
#include <utility>
#include <vector>

#include "core/geometry/light_frame.h"

namespace pdsm {
namespace {

constexpr int kWidth = 4;
constexpr int kHeight = 3;
constexpr float kStepDepth = 1.0f;

// A distinct value per pixel, so that a wrong pixel or weight shows.
double PixelValue(int i, int j) { return 0.05 + 0.1 * i + 0.3 * j; }

// Light at the origin looking along +z (u = +x, v = +y), window [-1, 1]^2, 4 x 3 pixels; pixel
// (i, j) is lit up to depth 1 and then hidden by PixelValue(i, j).
PdsmImage MakeImage(Projection projection) {
  PdsmImage image;
  PdsmGeometry& g = image.header.geometry;
  g.projection = projection;
  g.frame = LightFrame{};  // centre 0, u = +x, v = +y, n = +z
  g.width = kWidth;
  g.height = kHeight;
  g.s_min = g.t_min = -1;
  g.s_max = g.t_max = 1;
  g.z_near = 0.5;
  g.z_far = 10;
  image.offsets.push_back(0);
  for (int j = 0; j < kHeight; ++j) {
    for (int i = 0; i < kWidth; ++i) {
      image.vertices.push_back({kStepDepth, 0.0f});
      image.vertices.push_back({kStepDepth, static_cast<float>(PixelValue(i, j))});
      image.offsets.push_back(image.vertices.size());
    }
  }
  return image;
}

// The value the image holds behind the step (float, as stored).
double Stored(int i, int j) { return static_cast<float>(PixelValue(i, j)); }

// A world point on the ray through window coordinates (s, t) at light-space depth z.
glm::dvec3 PointAt(const PdsmImage& image, double s, double t, double z) {
  if (image.header.geometry.projection == Projection::kOrthographic) return {s, t, z};
  return {s * z, t * z, z};
}

class PdsmQueryTest : public testing::TestWithParam<Projection> {
 protected:
  PdsmImage image_ = MakeImage(GetParam());
  const PdsmGeometry& g() const { return image_.header.geometry; }
};

TEST_P(PdsmQueryTest, PixelCentreGivesThePixelsValue) {
  for (double z : {1.0, 2.0, 7.5}) {
    for (int j = 0; j < kHeight; ++j) {
      for (int i = 0; i < kWidth; ++i) {
        const glm::dvec3 p = PointAt(image_, g().PixelCenterS(i), g().PixelCenterT(j), z);
        EXPECT_NEAR(QueryAttenuation(image_, p), Stored(i, j), 1e-9)
            << "pixel " << i << "," << j << " z " << z;
      }
    }
  }
}

TEST_P(PdsmQueryTest, LitBeforeTheStep) {
  for (int j = 0; j < kHeight; ++j) {
    for (int i = 0; i < kWidth; ++i) {
      const glm::dvec3 p = PointAt(image_, g().PixelCenterS(i), g().PixelCenterT(j), 0.999);
      EXPECT_EQ(QueryAttenuation(image_, p), 0.0);
    }
  }
}

TEST_P(PdsmQueryTest, HalfwayBetweenCentresIsTheMean) {
  const double z = 3.0;
  // Along s.
  for (int j = 0; j < kHeight; ++j) {
    for (int i = 0; i + 1 < kWidth; ++i) {
      const double s = 0.5 * (g().PixelCenterS(i) + g().PixelCenterS(i + 1));
      EXPECT_NEAR(QueryAttenuation(image_, PointAt(image_, s, g().PixelCenterT(j), z)),
                  0.5 * (Stored(i, j) + Stored(i + 1, j)), 1e-9);
    }
  }
  // Along t.
  for (int j = 0; j + 1 < kHeight; ++j) {
    for (int i = 0; i < kWidth; ++i) {
      const double t = 0.5 * (g().PixelCenterT(j) + g().PixelCenterT(j + 1));
      EXPECT_NEAR(QueryAttenuation(image_, PointAt(image_, g().PixelCenterS(i), t, z)),
                  0.5 * (Stored(i, j) + Stored(i, j + 1)), 1e-9);
    }
  }
}

TEST_P(PdsmQueryTest, BilinearWeightsInTheInterior) {
  std::mt19937_64 rng(8);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int trial = 0; trial < 1000; ++trial) {
    const int i = static_cast<int>(unit(rng) * (kWidth - 1));
    const int j = static_cast<int>(unit(rng) * (kHeight - 1));
    const double wx = unit(rng), wy = unit(rng);
    const double s = g().PixelCenterS(i) + wx * g().PixelPitchS();
    const double t = g().PixelCenterT(j) + wy * g().PixelPitchT();
    const double z = 1.0 + 5.0 * unit(rng);
    const double expected = (1 - wy) * ((1 - wx) * Stored(i, j) + wx * Stored(i + 1, j)) +
                            wy * ((1 - wx) * Stored(i, j + 1) + wx * Stored(i + 1, j + 1));
    ASSERT_NEAR(QueryAttenuation(image_, PointAt(image_, s, t, z)), expected, 1e-9)
        << "trial " << trial;
  }
}

TEST_P(PdsmQueryTest, BorderClampsToEdgePixels) {
  const double z = 2.0;
  const double s_edge_lo = 0.5 * (g().s_min + g().PixelCenterS(0));
  const double s_edge_hi = 0.5 * (g().s_max + g().PixelCenterS(kWidth - 1));
  for (int j = 0; j < kHeight; ++j) {
    const double t = g().PixelCenterT(j);
    EXPECT_NEAR(QueryAttenuation(image_, PointAt(image_, s_edge_lo, t, z)), Stored(0, j), 1e-9);
    EXPECT_NEAR(QueryAttenuation(image_, PointAt(image_, s_edge_hi, t, z)), Stored(kWidth - 1, j),
                1e-9);
    // On the window's border itself.
    EXPECT_NEAR(QueryAttenuation(image_, PointAt(image_, g().s_min, t, z)), Stored(0, j), 1e-9);
    EXPECT_NEAR(QueryAttenuation(image_, PointAt(image_, g().s_max, t, z)), Stored(kWidth - 1, j),
                1e-9);
  }
  const double t_edge_lo = 0.5 * (g().t_min + g().PixelCenterT(0));
  const double t_edge_hi = g().t_max;
  for (int i = 0; i < kWidth; ++i) {
    const double s = g().PixelCenterS(i);
    EXPECT_NEAR(QueryAttenuation(image_, PointAt(image_, s, t_edge_lo, z)), Stored(i, 0), 1e-9);
    EXPECT_NEAR(QueryAttenuation(image_, PointAt(image_, s, t_edge_hi, z)), Stored(i, kHeight - 1),
                1e-9);
  }
  // Corners clamp in both directions.
  EXPECT_NEAR(QueryAttenuation(image_, PointAt(image_, g().s_min, g().t_min, z)), Stored(0, 0),
              1e-9);
  EXPECT_NEAR(QueryAttenuation(image_, PointAt(image_, g().s_max, g().t_max, z)),
              Stored(kWidth - 1, kHeight - 1), 1e-9);
  // Between the border and the centres along s, still bilinear in t.
  const double t_mid = 0.5 * (g().PixelCenterT(0) + g().PixelCenterT(1));
  EXPECT_NEAR(QueryAttenuation(image_, PointAt(image_, s_edge_lo, t_mid, z)),
              0.5 * (Stored(0, 0) + Stored(0, 1)), 1e-9);
}

TEST_P(PdsmQueryTest, OutsideTheWindowIsNaN) {
  const double z = 2.0;
  EXPECT_TRUE(std::isnan(QueryAttenuation(image_, PointAt(image_, 1.01, 0.0, z))));
  EXPECT_TRUE(std::isnan(QueryAttenuation(image_, PointAt(image_, -1.01, 0.0, z))));
  EXPECT_TRUE(std::isnan(QueryAttenuation(image_, PointAt(image_, 0.0, 1.01, z))));
  EXPECT_TRUE(std::isnan(QueryAttenuation(image_, PointAt(image_, 0.0, -1.01, z))));
  EXPECT_TRUE(std::isnan(QueryAttenuation(image_, PointAt(image_, 5.0, 5.0, z))));
}

TEST_P(PdsmQueryTest, ResultsAreAttenuations) {
  std::mt19937_64 rng(12);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int trial = 0; trial < 1000; ++trial) {
    const double s = -1 + 2 * unit(rng), t = -1 + 2 * unit(rng), z = 0.1 + 5 * unit(rng);
    const double a = QueryAttenuation(image_, PointAt(image_, s, t, z));
    ASSERT_GE(a, 0.0);
    ASSERT_LE(a, 1.0);
  }
}

// Refined pixels (core/pdsm/refined_pixel.h): pixels (1, 1) and (2, 1) refined 4x over the band
// [kBandLo, kBandHi), the rest as MakeImage; sub-pixel (a, b) of pixel (i, 1) hidden by
// SubValue(i, a, b) in the band, and each refined pixel keeps MakeImage's function as its own.
constexpr int kF = 4;
constexpr float kBandLo = 2.0f, kBandHi = 4.0f;
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
const std::vector<RefinedBand> kBand = {{kBandLo, kBandHi}};
double SubValue(int i, int a, int b) { return 0.02 + 0.03 * a + 0.15 * b + 0.25 * (i - 1); }
double StoredSub(int i, int a, int b) { return static_cast<float>(SubValue(i, a, b)); }

PdsmImage MakeRefinedImage(Projection projection) {
  const PdsmImage plain = MakeImage(projection);
  PdsmImage image;
  image.header = plain.header;
  image.header.max_refinement = kF;
  image.offsets.push_back(0);
  for (int j = 0; j < kHeight; ++j) {
    for (int i = 0; i < kWidth; ++i) {
      if (j == 1 && (i == 1 || i == 2)) {
        std::vector<std::vector<Vertex>> subs;
        for (int b = 0; b < kF; ++b) {
          for (int a = 0; a < kF; ++a) {
            const float v = static_cast<float>(SubValue(i, a, b));
            subs.push_back({{kUndefinedFrom, kNaN}, {kBandLo, v}, {kBandHi, v}, {kBandHi, kNaN}});
          }
        }
        AppendRefinedPixel(kF, kBand, plain.Function(i, j), subs, &image.vertices);
      } else {
        const std::span<const Vertex> f = plain.Function(i, j);
        image.vertices.insert(image.vertices.end(), f.begin(), f.end());
      }
      image.offsets.push_back(image.vertices.size());
    }
  }
  return image;
}

class RefinedQueryTest : public testing::TestWithParam<Projection> {
 protected:
  // The attenuation at pixel coordinates (px, py) (centres at k + 0.5) and depth z.
  double At(double px, double py, double z = 3.0) const {
    const PdsmGeometry& g = image_.header.geometry;
    return QueryAttenuation(
        image_, PointAt(image_, g.s_min + px * g.PixelPitchS(), g.t_min + py * g.PixelPitchT(), z));
  }
  PdsmImage image_ = MakeRefinedImage(GetParam());
};

TEST_P(RefinedQueryTest, ASubPixelCentreGivesItsValue) {
  for (int i : {1, 2}) {
    for (int b = 0; b < kF; ++b) {
      for (int a = 0; a < kF; ++a) {
        EXPECT_NEAR(At(i + (a + 0.5) / kF, 1 + (b + 0.5) / kF), StoredSub(i, a, b), 1e-9)
            << i << ": " << a << "," << b;
      }
    }
  }
}

TEST_P(RefinedQueryTest, OffItsBandsTheMapReadsAsUnrefined) {
  const PdsmImage plain = MakeImage(GetParam());
  const PdsmGeometry& g = plain.header.geometry;
  int inside_refined = 0;
  for (const double z : {0.999, 1.5, 1.999, 4.001, 4.5, 9.0}) {
    for (double py = 0.05; py < kHeight; py += 0.1) {
      for (double px = 0.05; px < kWidth; px += 0.1) {
        const glm::dvec3 p =
            PointAt(plain, g.s_min + px * g.PixelPitchS(), g.t_min + py * g.PixelPitchT(), z);
        ASSERT_EQ(QueryAttenuation(image_, p), QueryAttenuation(plain, p)) << px << "," << py;
        inside_refined += px > 1 && px < 3 && py > 1 && py < 2;
      }
    }
  }
  EXPECT_GT(inside_refined, 100);
}

TEST_P(RefinedQueryTest, BetweenSubPixelsIsBilinear) {
  // Halfway between sub-pixels (1, 2) and (2, 2) of pixel (1, 1), and a quarter of the way to
  // the row above.
  const double px = 1 + 2.0 / kF, py = 1 + (2.5 + 0.25) / kF;
  const double lower = 0.5 * (StoredSub(1, 1, 2) + StoredSub(1, 2, 2));
  const double upper = 0.5 * (StoredSub(1, 1, 3) + StoredSub(1, 2, 3));
  EXPECT_NEAR(At(px, py), 0.75 * lower + 0.25 * upper, 1e-9);
}

TEST_P(RefinedQueryTest, ANeighbourRefinedAlikeContinuesTheLattice) {
  // On the edge between pixels (1, 1) and (2, 1): the mean of the last column of one and the
  // first of the other, from either side.
  const double py = 1 + 1.5 / kF;
  const double mean = 0.5 * (StoredSub(1, kF - 1, 1) + StoredSub(2, 0, 1));
  EXPECT_NEAR(At(2.0, py), mean, 1e-9);
  EXPECT_NEAR(At(2.0 - 1e-9, py), mean, 1e-6);
}

TEST_P(RefinedQueryTest, AnUnrefinedNeighbourGivesItsOwnValueOnTheLattice) {
  // Pixel (0, 1) is not refined: inside (1, 1), left of its first sub-pixel centre, the point
  // blends that sub-pixel with the lattice ray a sub-pixel to its left, in (0, 1): (0, 1)'s own
  // value, not its centre's half a pixel away.
  const double py = 1 + 2.5 / kF;
  EXPECT_NEAR(At(1.0 + 0.1 / kF, py), 0.4 * Stored(0, 1) + 0.6 * StoredSub(1, 0, 2), 1e-9);
  // Pixel (1, 0) below is not refined either.
  EXPECT_NEAR(At(1 + 1.5 / kF, 1.0 + 0.1 / kF), 0.4 * Stored(1, 0) + 0.6 * StoredSub(1, 1, 0),
              1e-9);
}

TEST_P(RefinedQueryTest, BesideARefinedPixelItsOwnFunctionBlendsAsUnrefined) {
  // In pixel (0, 1), a quarter of the way from its centre to (1, 1)'s: the lattice rays around
  // the point lie in (0, 1), no sub-pixel is among them, and the pixels' own functions blend.
  const PdsmImage unrefined = MakeImage(GetParam());
  const PdsmGeometry& pg = unrefined.header.geometry;
  EXPECT_EQ(At(0.75, 1.5),
            QueryAttenuation(unrefined, PointAt(unrefined, pg.s_min + 0.75 * pg.PixelPitchS(),
                                                pg.t_min + 1.5 * pg.PixelPitchT(), 3.0)));
  // Pixels with no refined neighbour read exactly as before.
  const PdsmImage plain = MakeImage(GetParam());
  const PdsmGeometry& g = plain.header.geometry;
  for (const auto& [px, py] : {std::pair{3.3, 0.2}, std::pair{0.4, 2.9}, std::pair{3.9, 2.6}}) {
    const glm::dvec3 p =
        PointAt(plain, g.s_min + px * g.PixelPitchS(), g.t_min + py * g.PixelPitchT(), 3.0);
    EXPECT_EQ(QueryAttenuation(image_, p), QueryAttenuation(plain, p));
  }
}

INSTANTIATE_TEST_SUITE_P(Projections, RefinedQueryTest,
                         testing::Values(Projection::kPerspective, Projection::kOrthographic),
                         [](const testing::TestParamInfo<Projection>& info) {
                           return info.param == Projection::kPerspective ? "Perspective"
                                                                         : "Orthographic";
                         });

INSTANTIATE_TEST_SUITE_P(Projections, PdsmQueryTest,
                         testing::Values(Projection::kPerspective, Projection::kOrthographic),
                         [](const testing::TestParamInfo<Projection>& info) {
                           return info.param == Projection::kPerspective ? "Perspective"
                                                                         : "Orthographic";
                         });

TEST(PdsmQueryPerspectiveTest, BehindTheLightIsNaN) {
  const PdsmImage image = MakeImage(Projection::kPerspective);
  EXPECT_TRUE(std::isnan(QueryAttenuation(image, {0.0, 0.0, 0.0})));
  EXPECT_TRUE(std::isnan(QueryAttenuation(image, {0.1, 0.1, -1.0})));
  EXPECT_TRUE(std::isnan(QueryAttenuation(image, {0.0, 0.0, -5.0})));
}

TEST(PdsmQueryPerspectiveTest, ProjectsThroughTheLightCentre) {
  // The same direction at different depths lands in the same pixel: (0.75 z, 0.0 z, z) is
  // the ray of pixel (3, 1) whatever z.
  const PdsmImage image = MakeImage(Projection::kPerspective);
  for (double z : {1.5, 3.0, 9.0}) {
    EXPECT_NEAR(QueryAttenuation(image, {0.75 * z, 0.0, z}), Stored(3, 1), 1e-9);
  }
  // While the fixed offset x = 0.75 at depth 3 is s = 0.25: pixel (2, 1).
  EXPECT_NEAR(QueryAttenuation(image, {0.75, 0.0, 3.0}), Stored(2, 1), 1e-9);
}

TEST(PdsmQueryOrthographicTest, ParallelRays) {
  // Orthographic: s = x, t = y at any depth.
  const PdsmImage image = MakeImage(Projection::kOrthographic);
  for (double z : {1.5, 3.0, 9.0}) {
    EXPECT_NEAR(QueryAttenuation(image, {0.75, 0.0, z}), Stored(3, 1), 1e-9);
    EXPECT_NEAR(QueryAttenuation(image, {-0.75, -2.0 / 3.0, z}), Stored(0, 0), 1e-9);
  }
}

TEST(PdsmQueryFrameTest, RotatedFrameUsesLightSpace) {
  // The frame of core/bake tests: light at (0, 10, 0) facing -y, up +z: light x = world x,
  // light y = world z, depth = 10 - world y.
  PdsmImage image = MakeImage(Projection::kPerspective);
  const glm::dvec3 up(0, 0, 1);
  image.header.geometry.frame = MakeLightFrame({0, 10, 0}, {0, -1, 0}, &up);
  const double s = image.header.geometry.PixelCenterS(2);
  const double t = image.header.geometry.PixelCenterT(0);
  const double depth = 4.0;
  EXPECT_NEAR(QueryAttenuation(image, {s * depth, 10.0 - depth, t * depth}), Stored(2, 0), 1e-9);
  EXPECT_EQ(QueryAttenuation(image, {s * 0.5, 10.0 - 0.5, t * 0.5}), 0.0);
  EXPECT_TRUE(std::isnan(QueryAttenuation(image, {0.0, 11.0, 0.0})));
}

TEST(BilinearAttenuationTest, PixelCoordinates) {
  const PdsmImage image = MakeImage(Projection::kPerspective);
  EXPECT_NEAR(BilinearAttenuation(image, {0.5, 0.5, 2.0}), Stored(0, 0), 1e-9);
  EXPECT_NEAR(BilinearAttenuation(image, {1.0, 0.5, 2.0}), 0.5 * (Stored(0, 0) + Stored(1, 0)),
              1e-9);
  EXPECT_NEAR(BilinearAttenuation(image, {3.5, 2.5, 2.0}), Stored(3, 2), 1e-9);
  EXPECT_NEAR(BilinearAttenuation(image, {0.0, 0.0, 2.0}), Stored(0, 0), 1e-9);
  EXPECT_NEAR(BilinearAttenuation(image, {4.0, 3.0, 2.0}), Stored(3, 2), 1e-9);
  EXPECT_EQ(BilinearAttenuation(image, {1.0, 1.0, 0.5}), 0.0);
}

}  // namespace
}  // namespace pdsm
