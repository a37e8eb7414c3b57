#include "core/reference/exact_visibility.h"

// Boost 1.74 rescales overlay input to integers by default, which costs ~1e-7 of accuracy;
// without it, it agrees with the implementation to 1e-16 in general position.
#define BOOST_GEOMETRY_NO_ROBUSTNESS
// Boost 1.74's overlay code trips GCC 12's -Wmaybe-uninitialized (false alarms).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <boost/geometry.hpp>
#include <boost/geometry/geometries/multi_polygon.hpp>
#include <boost/geometry/geometries/polygon.hpp>
#include <boost/geometry/geometries/register/point.hpp>
#pragma GCC diagnostic pop
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <random>
#include <utility>
#include <vector>

#include "absl/status/status.h"
#include "core/geometry/light_frame.h"
#include "core/scene/scene.h"

// A point type of this file's own (internal linkage), so the Boost templates instantiated
// here with BOOST_GEOMETRY_NO_ROBUSTNESS cannot collide with another file's instantiations.
namespace {
struct OraclePoint {
  double x, y;
};
}  // namespace
BOOST_GEOMETRY_REGISTER_POINT_2D(OraclePoint, double, boost::geometry::cs::cartesian, x, y)

namespace pdsm {
namespace {

using Tris = std::vector<glm::dvec3>;
using Polygon = std::vector<glm::dvec2>;

Polygon Rect(double x0, double y0, double x1, double y1) {
  return {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
}

// Axis-aligned rectangle at height z as two triangles (counter-clockwise seen from +z).
void AddRectAtZ(double x0, double y0, double x1, double y1, double z, Tris* tris) {
  tris->insert(tris->end(), {{x0, y0, z}, {x1, y0, z}, {x1, y1, z}});
  tris->insert(tris->end(), {{x0, y0, z}, {x1, y1, z}, {x0, y1, z}});
}

double Hidden(const Polygon& light, const Tris& tris, const glm::dvec3& p) {
  return ExactHiddenFraction(light, tris, p);
}

// Möller–Trumbore: does the segment from o to o + d (parameter in (0, 1)) cross triangle abc?
bool SegmentHitsTriangle(const glm::dvec3& o, const glm::dvec3& d, const glm::dvec3& a,
                         const glm::dvec3& b, const glm::dvec3& c) {
  const glm::dvec3 e1 = b - a, e2 = c - a;
  const glm::dvec3 pvec = glm::cross(d, e2);
  const double det = glm::dot(e1, pvec);
  if (std::abs(det) < 1e-300) return false;
  const double inv_det = 1.0 / det;
  const glm::dvec3 tvec = o - a;
  const double u = glm::dot(tvec, pvec) * inv_det;
  if (u < 0.0 || u > 1.0) return false;
  const glm::dvec3 qvec = glm::cross(tvec, e1);
  const double v = glm::dot(d, qvec) * inv_det;
  if (v < 0.0 || u + v > 1.0) return false;
  const double t = glm::dot(e2, qvec) * inv_det;
  return t > 0.0 && t < 1.0;
}

bool InsidePolygon(const Polygon& poly, const glm::dvec2& q) {
  bool inside = false;
  for (size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
    const glm::dvec2 a = poly[i], b = poly[j];
    if ((a.y > q.y) != (b.y > q.y) && q.x < (b.x - a.x) * (q.y - a.y) / (b.y - a.y) + a.x) {
      inside = !inside;
    }
  }
  return inside;
}

// The hidden share of uniformly drawn light points (rejection sampling), each weighted as
// `weighting` says (light_weighting.h), computed here per sample from its definition: the ratio
// estimate and its standard error.
struct WeightedEstimate {
  double value = 0.0, standard_error = 0.0;
};
WeightedEstimate MonteCarloWeighted(const Polygon& light, const Tris& tris, const glm::dvec3& p,
                                    LightWeighting weighting, const glm::dvec3& normal, int samples,
                                    uint64_t seed) {
  glm::dvec2 lo = light[0], hi = light[0];
  for (const glm::dvec2& q : light) {
    lo = glm::min(lo, q);
    hi = glm::max(hi, q);
  }
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> ux(lo.x, hi.x), uy(lo.y, hi.y);
  std::vector<std::pair<double, bool>> drawn;  // weight, hidden
  double sum_w = 0.0, sum_wh = 0.0;
  for (int s = 0; s < samples;) {
    const glm::dvec2 q(ux(rng), uy(rng));
    if (!InsidePolygon(light, q)) continue;
    ++s;
    const glm::dvec3 d = glm::dvec3(q, 0.0) - p;
    const double r = glm::length(d);
    double w = 1.0;
    if (weighting != LightWeighting::kUnweighted) w = (p.z / r) / (r * r);  // cos_light / r^2
    if (weighting == LightWeighting::kIrradiance) w *= std::max(0.0, glm::dot(normal, d) / r);
    bool hidden = false;
    for (size_t t = 0; t < tris.size() && !hidden; t += 3) {
      hidden = SegmentHitsTriangle(p, d, tris[t], tris[t + 1], tris[t + 2]);
    }
    drawn.emplace_back(w, hidden);
    sum_w += w;
    sum_wh += hidden ? w : 0.0;
  }
  WeightedEstimate e;
  e.value = sum_wh / sum_w;
  double variance = 0.0;  // the ratio estimator's (delta method)
  for (const auto& [w, hidden] : drawn) {
    const double r = w * ((hidden ? 1.0 : 0.0) - e.value);
    variance += r * r;
  }
  e.standard_error = std::sqrt(variance) / sum_w;
  return e;
}

// Fraction of uniformly drawn light points whose segment to p is blocked.
double MonteCarloHidden(const Polygon& light, const Tris& tris, const glm::dvec3& p, int samples,
                        uint64_t seed) {
  return MonteCarloWeighted(light, tris, p, LightWeighting::kUnweighted, glm::dvec3(0.0), samples,
                            seed)
      .value;
}

Tris RandomTriangles(int count, double size, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> cx(-1.5, 1.5), cz(-0.5, 2.5), off(-size, size);
  Tris tris;
  for (int i = 0; i < count; ++i) {
    const glm::dvec3 centre(cx(rng), cx(rng), cz(rng));
    for (int k = 0; k < 3; ++k) tris.push_back(centre + glm::dvec3(off(rng), off(rng), off(rng)));
  }
  return tris;
}

void ExpectMatchesMonteCarlo(const Polygon& light, const Tris& tris, const glm::dvec3& p,
                             uint64_t seed) {
  constexpr int kSamples = 200000;
  const double exact = Hidden(light, tris, p);
  const double mc = MonteCarloHidden(light, tris, p, kSamples, seed);
  const double standard_error = std::sqrt(std::max(exact * (1.0 - exact), 1e-6) / kSamples);
  EXPECT_NEAR(exact, mc, 4.0 * standard_error) << "seed " << seed;
  // A configuration far from 0 and 1, so the comparison means something.
  EXPECT_GT(mc, 0.02) << "seed " << seed;
  EXPECT_LT(mc, 0.98) << "seed " << seed;
}

// Independent oracle: Boost.Geometry booleans on triangles wholly between light and point
// (no clipping needed) in general position, where Boost 1.74 is reliable. It is not on
// meshes with shared edges, which is why the implementation does not use it.
double BoostHidden(const Polygon& light, const Tris& tris, const glm::dvec3& p) {
  namespace bg = boost::geometry;
  using BgPolygon = bg::model::polygon<OraclePoint>;
  using BgMulti = bg::model::multi_polygon<BgPolygon>;
  BgPolygon light_bg;
  for (const glm::dvec2& q : light) bg::append(light_bg.outer(), OraclePoint{q.x, q.y});
  bg::correct(light_bg);
  BgMulti hidden;
  for (size_t t = 0; t < tris.size(); t += 3) {
    BgPolygon projected;
    for (int k = 0; k < 3; ++k) {
      const glm::dvec3& v = tris[t + k];
      EXPECT_GT(v.z, 0.0);
      EXPECT_LT(v.z, p.z);
      const glm::dvec2 q = glm::dvec2(p) + (glm::dvec2(v) - glm::dvec2(p)) * (p.z / (p.z - v.z));
      bg::append(projected.outer(), OraclePoint{q.x, q.y});
    }
    bg::correct(projected);
    BgMulti clipped, merged;
    bg::intersection(projected, light_bg, clipped);
    bg::union_(hidden, clipped, merged);
    hidden = std::move(merged);
  }
  return bg::area(hidden) / bg::area(light_bg);
}

const Polygon kUnitLight = Rect(-1, -1, 1, 1);  // area 4

TEST(ExactHiddenFractionTest, NoOccludersIsLit) {
  EXPECT_EQ(Hidden(kUnitLight, {}, {0.3, 0.2, 2.0}), 0.0);
}

TEST(ExactHiddenFractionTest, HugeOccluderIsUmbra) {
  Tris tris;
  AddRectAtZ(-100, -100, 100, 100, 1.0, &tris);
  // Vertices cut from 200-unit edges carry ~1e-14 of rounding.
  EXPECT_NEAR(Hidden(kUnitLight, tris, {0.3, 0.2, 2.0}), 1.0, 1e-12);
}

TEST(ExactHiddenFractionTest, OccluderBehindPointOrLightHidesNothing) {
  Tris behind_point, behind_light;
  AddRectAtZ(-100, -100, 100, 100, 3.0, &behind_point);
  AddRectAtZ(-100, -100, 100, 100, -1.0, &behind_light);
  EXPECT_EQ(Hidden(kUnitLight, behind_point, {0.0, 0.0, 2.0}), 0.0);
  EXPECT_EQ(Hidden(kUnitLight, behind_light, {0.0, 0.0, 2.0}), 0.0);
}

TEST(ExactHiddenFractionTest, PointBehindLightSeesNothingBetween) {
  Tris tris;
  AddRectAtZ(-100, -100, 100, 100, 1.0, &tris);
  EXPECT_EQ(Hidden(kUnitLight, tris, {0.0, 0.0, -2.0}), 0.0);
}

TEST(ExactHiddenFractionTest, DegenerateLightHidesNothing) {
  Tris tris;
  AddRectAtZ(-100, -100, 100, 100, 1.0, &tris);
  EXPECT_EQ(Hidden(Rect(-1, 0, 1, 0), tris, {0.0, 0.0, 2.0}), 0.0);
}

TEST(ExactHiddenFractionTest, HalfPlaneAtHalfHeightHidesHalf) {
  Tris tris;
  AddRectAtZ(0, -5, 5, 5, 1.0, &tris);
  EXPECT_NEAR(Hidden(kUnitLight, tris, {0.0, 0.0, 2.0}), 0.5, 1e-12);
}

// The occluder's edge x = 0 at z = 1 projects from (s, 0, 2) to X = -s, so a square light
// sees a hidden share (1 + s) / 2: linear across the penumbra, 0 and 1 outside it.
TEST(ExactHiddenFractionTest, PenumbraOfStraightEdgeIsLinearForSquareLight) {
  Tris tris;
  AddRectAtZ(0, -50, 50, 50, 1.0, &tris);
  for (double s : {-1.5, -1.0, -0.75, -0.3, 0.0, 0.1, 0.5, 0.9, 1.0, 2.0}) {
    const double expected = std::clamp((1.0 + s) / 2.0, 0.0, 1.0);
    EXPECT_NEAR(Hidden(kUnitLight, tris, {s, 0.25, 2.0}), expected, 1e-12) << "s = " << s;
  }
}

// Same edge at z = z_occ seen from height h: X = s + (0 - s) h / (h - z_occ).
TEST(ExactHiddenFractionTest, PenumbraDependsOnOccluderHeight) {
  const double h = 4.0;
  for (double z_occ : {0.5, 1.0, 2.0, 3.0}) {
    Tris tris;
    AddRectAtZ(0, -500, 500, 500, z_occ, &tris);
    const double s = 0.2;
    const double edge = s - s * h / (h - z_occ);
    const double expected = std::clamp((1.0 - edge) / 2.0, 0.0, 1.0);
    EXPECT_NEAR(Hidden(kUnitLight, tris, {s, 0.0, h}), expected, 1e-12) << "z_occ " << z_occ;
  }
}

TEST(ExactHiddenFractionTest, SmallOccluderInsideProjectionHidesScaledArea) {
  const double side = 0.2, z_occ = 1.0;
  const glm::dvec3 p(0.1, -0.05, 3.0);
  Tris tris;
  AddRectAtZ(-side / 2, -side / 2, side / 2, side / 2, z_occ, &tris);
  const double projected_side = side * p.z / (p.z - z_occ);
  EXPECT_NEAR(Hidden(kUnitLight, tris, p), projected_side * projected_side / 4.0, 1e-12);
}

TEST(ExactHiddenFractionTest, OverlappingTrianglesAreNotCountedTwice) {
  // The square's lower-left half twice (identical duplicates) plus its upper-right half.
  Tris overlapping = {{-0.3, -0.3, 1}, {0.3, -0.3, 1}, {-0.3, 0.3, 1},
                      {-0.3, -0.3, 1}, {0.3, -0.3, 1}, {-0.3, 0.3, 1},
                      {0.3, 0.3, 1},   {-0.3, 0.3, 1}, {0.3, -0.3, 1}};
  Tris square;
  AddRectAtZ(-0.3, -0.3, 0.3, 0.3, 1.0, &square);
  const glm::dvec3 p(0.05, 0.1, 2.0);
  EXPECT_NEAR(Hidden(kUnitLight, overlapping, p), Hidden(kUnitLight, square, p), 1e-12);
  EXPECT_NEAR(Hidden(kUnitLight, square, p), 1.2 * 1.2 / 4.0, 1e-12);
}

TEST(ExactHiddenFractionTest, PartlyOverlappingTrianglesMatchTheirUnion) {
  // Two wedges of T = (0,0),(2,0),(0,2) from its corner at the origin, overlapping between
  // the rays to (1.2, 0.8) and (0.5, 1.5): their union is T.
  const double z = 1.0;
  Tris pieces = {{0, 0, z}, {2, 0, z},     {0.5, 1.5, z},  // right part of T
                 {0, 0, z}, {1.2, 0.8, z}, {0, 2, z}};     // left part, overlapping the first
  Tris whole = {{0, 0, z}, {2, 0, z}, {0, 2, z}};
  // Scale everything into the light: seen from (0,0,2) at z = 1 projections double.
  for (glm::dvec3& v : pieces) v = glm::dvec3(v.x * 0.4 - 0.5, v.y * 0.4 - 0.5, v.z);
  for (glm::dvec3& v : whole) v = glm::dvec3(v.x * 0.4 - 0.5, v.y * 0.4 - 0.5, v.z);
  const glm::dvec3 p(0.0, 0.0, 2.0);
  // Whole triangle: legs 0.8 at z = 1, doubled to 1.6: area 1.28 of 4.
  EXPECT_NEAR(Hidden(kUnitLight, whole, p), 1.28 / 4.0, 1e-12);
  EXPECT_NEAR(Hidden(kUnitLight, pieces, p), 1.28 / 4.0, 1e-12);
}

TEST(ExactHiddenFractionTest, ClosedCubeCountsItsSilhouetteOnce) {
  // Cube [-0.25, 0.25]^2 x [0.8, 1.2] on the axis below p = (0, 0, 2): its silhouette is the
  // top face, projected with scale 2 / (2 - 1.2) = 2.5 to a square of side 1.25.
  const double a = 0.25, z0 = 0.8, z1 = 1.2;
  const glm::dvec3 c[8] = {{-a, -a, z0}, {a, -a, z0}, {a, a, z0}, {-a, a, z0},
                           {-a, -a, z1}, {a, -a, z1}, {a, a, z1}, {-a, a, z1}};
  const int faces[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4},
                           {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
  Tris tris;
  for (const auto& f : faces) {
    tris.insert(tris.end(), {c[f[0]], c[f[1]], c[f[2]], c[f[0]], c[f[2]], c[f[3]]});
  }
  EXPECT_NEAR(Hidden(kUnitLight, tris, {0.0, 0.0, 2.0}), 1.25 * 1.25 / 4.0, 1e-12);
}

// A finely tessellated tilted plate (shared edges, random diagonals, mixed windings) hides
// exactly what the same plate as two triangles hides.
TEST(ExactHiddenFractionTest, TessellatedPlateMatchesSinglePlate) {
  auto height = [](double x, double y) { return 1.0 + 0.2 * x + 0.1 * y; };
  auto vertex = [&](double x, double y) { return glm::dvec3(x, y, height(x, y)); };
  const double x0 = -0.6, x1 = 0.4, y0 = -0.5, y1 = 0.7;
  const int n = 40;
  std::mt19937_64 rng(7);
  Tris fine;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      const double xa = x0 + (x1 - x0) * i / n, xb = x0 + (x1 - x0) * (i + 1) / n;
      const double ya = y0 + (y1 - y0) * j / n, yb = y0 + (y1 - y0) * (j + 1) / n;
      const glm::dvec3 a = vertex(xa, ya), b = vertex(xb, ya), c = vertex(xb, yb),
                       d = vertex(xa, yb);
      if (rng() % 2 == 0) {
        fine.insert(fine.end(), {a, b, c, a, c, d});
      } else {
        fine.insert(fine.end(), {a, b, d, d, c, b});  // other diagonal, second one clockwise
      }
    }
  }
  const Tris coarse = {vertex(x0, y0), vertex(x1, y0), vertex(x1, y1),
                       vertex(x0, y0), vertex(x1, y1), vertex(x0, y1)};
  for (const glm::dvec3& p :
       {glm::dvec3(0.0, 0.0, 2.0), glm::dvec3(0.7, -0.4, 1.8), glm::dvec3(-1.5, 1.0, 3.0)}) {
    const double expected = Hidden(kUnitLight, coarse, p);
    EXPECT_GT(expected, 0.05);
    EXPECT_NEAR(Hidden(kUnitLight, fine, p), expected, 1e-9);
  }
}

TEST(ExactHiddenFractionTest, TriangleCrossingLightPlaneIsClipped) {
  // Triangle A B C with A below the light plane. Its part at z >= 0, cut by hand: the edges
  // from A cross z = 0 at (0, -3, 0) and (0, -0.6, 0).
  const glm::dvec3 a(-1, -3, -1), b(1.5, -3, 1.5), c(1.5, 3, 1.5);
  const glm::dvec3 ab0(0, -3, 0), ac0(0, -0.6, 0);
  const Tris whole = {a, b, c};
  const Tris pre_clipped = {ab0, b, c, ab0, c, ac0};
  const glm::dvec3 p(0.5, 0.0, 2.0);
  const double expected = Hidden(kUnitLight, pre_clipped, p);
  EXPECT_GT(expected, 0.05);
  EXPECT_LT(expected, 0.95);
  EXPECT_NEAR(Hidden(kUnitLight, whole, p), expected, 1e-12);
  // And it is right, not just consistent.
  EXPECT_NEAR(expected, MonteCarloHidden(kUnitLight, whole, p, 200000, 11), 4e-3);
}

TEST(ExactHiddenFractionTest, TriangleCrossingPointHeightIsClipped) {
  // A, B, C on the plane z = 1 + y / 2; p = (0, 0, 2) is off it. The edges to C cross z = 2 at
  // (-0.075, 2, 2) and (0.075, 2, 2); the part above z = 2 hides nothing.
  const glm::dvec3 a(-0.3, -1, 0.5), b(0.3, -1, 0.5), c(0, 3, 2.5);
  const glm::dvec3 ac2(-0.075, 2, 2), bc2(0.075, 2, 2);
  const glm::dvec3 p(0.0, 0.0, 2.0);
  const Tris whole = {a, b, c};
  const Tris below = {a, b, bc2, a, bc2, ac2};
  const Tris above = {ac2, bc2, c};
  const double expected = Hidden(kUnitLight, below, p);
  EXPECT_GT(expected, 0.05);
  EXPECT_LT(expected, 0.95);
  EXPECT_NEAR(Hidden(kUnitLight, whole, p), expected, 1e-8);
  EXPECT_EQ(Hidden(kUnitLight, above, p), 0.0);
  EXPECT_NEAR(expected, MonteCarloHidden(kUnitLight, whole, p, 200000, 12), 4e-3);
}

TEST(ExactHiddenFractionTest, SurfaceThroughThePointHidesNothing) {
  const glm::dvec3 p(0.1, 0.2, 2.0);
  // Flat and tilted plates through p: their projections from p are lines.
  Tris flat, tilted;
  AddRectAtZ(-5, -5, 5, 5, 2.0, &flat);
  auto on_tilted = [&](double x, double y) { return glm::dvec3(x, y, p.z + 0.3 * (x - p.x)); };
  tilted = {on_tilted(-1, -1), on_tilted(1, -1), on_tilted(1, 1),
            on_tilted(-1, -1), on_tilted(1, 1),  on_tilted(-1, 1)};
  EXPECT_EQ(Hidden(kUnitLight, flat, p), 0.0);
  EXPECT_LT(Hidden(kUnitLight, tilted, p), 1e-6);
}

TEST(ExactHiddenFractionTest, OrientationIndependent) {
  const Tris ccw = RandomTriangles(15, 0.8, 3);
  Tris cw = ccw;
  for (size_t t = 0; t < cw.size(); t += 3) std::swap(cw[t + 1], cw[t + 2]);
  Polygon light_cw = kUnitLight;
  std::reverse(light_cw.begin(), light_cw.end());
  const glm::dvec3 p(0.2, -0.1, 2.2);
  const double reference = Hidden(kUnitLight, ccw, p);
  EXPECT_GT(reference, 0.02);
  EXPECT_NEAR(Hidden(kUnitLight, cw, p), reference, 1e-12);
  EXPECT_NEAR(Hidden(light_cw, ccw, p), reference, 1e-12);
  EXPECT_NEAR(Hidden(light_cw, cw, p), reference, 1e-12);
}

TEST(ExactHiddenFractionTest, MatchesMonteCarloForRandomTriangles) {
  for (uint64_t seed : {1, 2, 3, 4}) {
    ExpectMatchesMonteCarlo(Rect(-1, -0.5, 1, 0.5), RandomTriangles(20, 0.8, seed),
                            {0.2 * seed - 0.5, 0.1, 2.0}, 100 + seed);
  }
}

TEST(ExactHiddenFractionTest, MatchesBoostGeometryInGeneralPosition) {
  const Polygon lights[] = {Rect(-1, -0.5, 1, 0.5),
                            {{-1, -1}, {1, -1}, {1, 0}, {0, 0}, {0, 1}, {-1, 1}}};
  for (const Polygon& light : lights) {
    for (uint64_t seed : {31, 32, 33}) {
      std::mt19937_64 rng(seed);
      std::uniform_real_distribution<double> xy(-1.5, 1.5), z(0.2, 1.5), off(-0.4, 0.4);
      Tris tris;
      for (int i = 0; i < 40; ++i) {
        const glm::dvec3 centre(xy(rng), xy(rng), 0.0);
        for (int k = 0; k < 3; ++k) {
          tris.push_back(centre + glm::dvec3(off(rng), off(rng), z(rng)));
        }
      }
      const glm::dvec3 p(0.1, -0.2, 2.0);
      const double boost_value = BoostHidden(light, tris, p);
      EXPECT_GT(boost_value, 0.05);
      EXPECT_NEAR(Hidden(light, tris, p), boost_value, 1e-12) << "seed " << seed;
    }
  }
}

// A closed UV sphere: many shared edges, front and back faces over each other.
TEST(ExactHiddenFractionTest, ClosedMeshMatchesMonteCarlo) {
  const glm::dvec3 centre(0.6, 0.2, 1.0);
  const double radius = 0.3;
  const int rings = 12, segments = 24;
  auto at = [&](int r, int s) {
    const double theta = std::numbers::pi * r / rings, phi = 2.0 * std::numbers::pi * s / segments;
    return centre + radius * glm::dvec3(std::sin(theta) * std::cos(phi),
                                        std::sin(theta) * std::sin(phi), std::cos(theta));
  };
  Tris tris;
  for (int r = 0; r < rings; ++r) {
    for (int s = 0; s < segments; ++s) {
      const glm::dvec3 a = at(r, s), b = at(r + 1, s), c = at(r + 1, s + 1), d = at(r, s + 1);
      if (r > 0) tris.insert(tris.end(), {a, b, d});
      if (r + 1 < rings) tris.insert(tris.end(), {b, c, d});
    }
  }
  ExpectMatchesMonteCarlo(kUnitLight, tris, {0.0, 0.0, 2.0}, 501);
}

TEST(ExactHiddenFractionTest, MatchesMonteCarloForManySmallTriangles) {
  // A "leaf cloud": hundreds of small, heavily overlapping triangles.
  ExpectMatchesMonteCarlo(kUnitLight, RandomTriangles(300, 0.25, 21), {0.1, 0.0, 2.6}, 201);
}

TEST(ExactHiddenFractionTest, MatchesMonteCarloForNonConvexLight) {
  const Polygon l_shape = {{-1, -1}, {1, -1}, {1, 0}, {0, 0}, {0, 1}, {-1, 1}};
  for (uint64_t seed : {5, 6}) {
    ExpectMatchesMonteCarlo(l_shape, RandomTriangles(20, 0.8, seed), {0.0, 0.3, 2.0}, 300 + seed);
  }
}

TEST(ExactHiddenFractionTest, MatchesMonteCarloForPolygonalDisk) {
  Polygon disk;
  for (int k = 0; k < 64; ++k) {
    const double angle = 2.0 * std::numbers::pi * k / 64;
    disk.emplace_back(std::cos(angle), std::sin(angle));
  }
  ExpectMatchesMonteCarlo(disk, RandomTriangles(25, 0.7, 9), {-0.2, 0.1, 2.0}, 401);
}

// --- ExactAttenuation on a scene built in code --------------------------------------------

// Light centred at (0, 10, 0) facing -y; caster: the half-plane x >= 0 at y = 5.
Scene HalfPlaneScene(LightShape shape) {
  Scene scene;
  scene.name = "half_plane";
  const glm::dvec3 up(0, 0, 1);
  scene.light.shape = shape;
  scene.light.frame = MakeLightFrame({0, 10, 0}, {0, -1, 0}, &up);
  scene.light.half_width = 1.0;
  scene.light.half_height = 1.0;
  scene.light.radius = 1.0;
  scene.light.tan_half_angle = 0.01;
  TriangleMesh caster;
  caster.label = "meshes[0] (inline)";
  caster.positions_world = {{0, 5, -50}, {50, 5, -50}, {50, 5, 50}, {0, 5, 50}};
  caster.indices = {0, 1, 2, 0, 2, 3};
  scene.meshes.push_back(caster);
  // A receiver-only mesh between everything and the light must cast nothing.
  TriangleMesh floor;
  floor.label = "meshes[1] (inline)";
  floor.role = MeshRole::kReceiverOnly;
  floor.positions_world = {{-50, 7, -50}, {50, 7, -50}, {50, 7, 50}, {-50, 7, 50}};
  floor.indices = {0, 1, 2, 0, 2, 3};
  scene.meshes.push_back(floor);
  return scene;
}

TEST(ExactAttenuationTest, RectLightHalfPlane) {
  const Scene scene = HalfPlaneScene(LightShape::kRect);
  // From (s, 0, 0) the edge projects to x = -s on the light: hidden share (1 + s) / 2.
  const std::vector<glm::dvec3> points = {{0, 0, 0},  {0.5, 0, 0.3}, {-0.5, 0, 0}, {5, 0, 0},
                                          {-5, 0, 0}, {0, 11, 0},    {0, 10, 0}};
  absl::StatusOr<std::vector<double>> a = ExactAttenuation(scene, points);
  ASSERT_TRUE(a.ok()) << a.status();
  ASSERT_EQ(a->size(), points.size());
  EXPECT_NEAR((*a)[0], 0.5, 1e-12);
  EXPECT_NEAR((*a)[1], 0.75, 1e-12);
  EXPECT_NEAR((*a)[2], 0.25, 1e-12);
  EXPECT_DOUBLE_EQ((*a)[3], 1.0);
  EXPECT_EQ((*a)[4], 0.0);
  EXPECT_TRUE(std::isnan((*a)[5]));  // behind the light
  EXPECT_TRUE(std::isnan((*a)[6]));  // on the light plane
}

TEST(ExactAttenuationTest, DiskLightMatchesAnalyticSegments) {
  const Scene scene = HalfPlaneScene(LightShape::kDisk);
  const std::vector<glm::dvec3> points = {{0, 0, 0}, {5, 0, 0}, {-5, 0, 0}, {0.5, 0, 0}};
  absl::StatusOr<std::vector<double>> a = ExactAttenuation(scene, points);
  ASSERT_TRUE(a.ok()) << a.status();
  EXPECT_NEAR((*a)[0], 0.5, 1e-12);  // the 512-gon is symmetric about the edge's line
  EXPECT_DOUBLE_EQ((*a)[1], 1.0);    // full umbra
  EXPECT_EQ((*a)[2], 0.0);           // fully lit
  // Edge at x = -0.5 on the unit disk: all but the circular segment beyond the chord at
  // distance 0.5 is hidden. The 512-gon differs from the disk by < 3e-5 of its area.
  const double d = 0.5;
  const double segment = std::acos(d) - d * std::sqrt(1.0 - d * d);
  EXPECT_NEAR((*a)[3], 1.0 - segment / std::numbers::pi, 1e-4);
}

TEST(ExactAttenuationTest, SunIsUnimplemented) {
  const Scene scene = HalfPlaneScene(LightShape::kSun);
  const std::vector<glm::dvec3> points = {{0, 0, 0}};
  EXPECT_EQ(ExactAttenuation(scene, points).status().code(), absl::StatusCode::kUnimplemented);
}

TEST(ExactAttenuationTest, BadIndexIsInvalidArgument) {
  Scene scene = HalfPlaneScene(LightShape::kRect);
  scene.meshes[0].indices.push_back(0);
  scene.meshes[0].indices.push_back(1);
  scene.meshes[0].indices.push_back(99);
  const std::vector<glm::dvec3> points = {{0, 0, 0}};
  EXPECT_EQ(ExactAttenuation(scene, points).status().code(), absl::StatusCode::kInvalidArgument);
}

TEST(ExactAttenuationTest, ManyPointsKeepTheirOrder) {
  // Threads share the points out; every output slot must still belong to its point.
  const Scene scene = HalfPlaneScene(LightShape::kRect);
  std::vector<glm::dvec3> points;
  for (int i = 0; i <= 200; ++i) points.emplace_back(-1.2 + 2.4 * i / 200.0, 0.0, 0.1 * i);
  absl::StatusOr<std::vector<double>> a = ExactAttenuation(scene, points);
  ASSERT_TRUE(a.ok()) << a.status();
  for (size_t i = 0; i < points.size(); ++i) {
    const double s = points[i].x;
    EXPECT_NEAR((*a)[i], std::clamp((1.0 + s) / 2.0, 0.0, 1.0), 1e-12) << "point " << i;
  }
}

// Weighted attenuation (issue #15 item 4). A half-plane occluder whose edge projects onto the
// light's middle from a point off to one side: half the light's area is hidden, but the hidden
// half is the far one, so it covers less than half the solid angle.
TEST(ExactWeightedTest, AHalfHiddenFromTheSideIsLessThanHalfWeighted) {
  const Polygon light = Rect(-1, -1, 1, 1);
  const glm::dvec3 p(1.5, 0.3, 2.0);
  const glm::dvec3 normal = glm::normalize(glm::dvec3(0.1, 0.0, -1.0));
  // The edge at height z_occ through the line that projects to x = 0: x = p.x (1 - h'/h).
  const double z_occ = 1.0;
  const double edge = p.x * (1.0 - (p.z - z_occ) / p.z);
  Tris tris;
  AddRectAtZ(-50, -50, edge, 50, z_occ, &tris);
  EXPECT_NEAR(ExactHiddenFraction(light, tris, p), 0.5, 1e-12);
  for (LightWeighting w : {LightWeighting::kEmitter, LightWeighting::kIrradiance}) {
    const double exact = ExactHiddenFraction(light, tris, p, w, normal);
    const WeightedEstimate mc = MonteCarloWeighted(light, tris, p, w, normal, 200000, 7);
    EXPECT_NEAR(exact, mc.value, 4.0 * mc.standard_error) << LightWeightingName(w);
    EXPECT_LT(exact, 0.45) << LightWeightingName(w);  // a definition that differs, measurably
  }
}

TEST(ExactWeightedTest, MatchesWeightedMonteCarloForRandomTriangles) {
  const glm::dvec3 normal = glm::normalize(glm::dvec3(-0.2, 0.1, -1.0));
  for (uint64_t seed : {1, 2, 3}) {
    const Polygon light = Rect(-1, -0.5, 1, 0.5);
    const Tris tris = RandomTriangles(20, 0.8, seed);
    const glm::dvec3 p(0.3 * seed - 0.6, 0.1, 2.0);
    for (LightWeighting w : {LightWeighting::kEmitter, LightWeighting::kIrradiance}) {
      const double exact = ExactHiddenFraction(light, tris, p, w, normal);
      const WeightedEstimate mc = MonteCarloWeighted(light, tris, p, w, normal, 200000, 50 + seed);
      EXPECT_NEAR(exact, mc.value, 4.0 * mc.standard_error)
          << LightWeightingName(w) << " seed " << seed;
      EXPECT_GT(mc.value, 0.02);
      EXPECT_LT(mc.value, 0.98);
    }
  }
}

TEST(ExactWeightedTest, NoOccluderIsLitAndFullCoverIsUmbraInEveryMeasure) {
  const Polygon light = Rect(-1, -1, 1, 1);
  const glm::dvec3 p(0.4, -0.2, 3.0);
  const glm::dvec3 normal(0.0, 0.0, -1.0);
  Tris cover;
  AddRectAtZ(-100, -100, 100, 100, 1.0, &cover);
  for (LightWeighting w : {LightWeighting::kEmitter, LightWeighting::kIrradiance}) {
    EXPECT_EQ(ExactHiddenFraction(light, {}, p, w, normal), 0.0);
    EXPECT_NEAR(ExactHiddenFraction(light, cover, p, w, normal), 1.0, 1e-12);
  }
}

// The receiver's cosine is integrated with its sign, so a light reaching behind the receiver's
// plane is refused (NaN), not measured wrong.
TEST(ExactWeightedTest, IrradianceIsNotMeasuredWhereTheLightReachesBehindTheReceiver) {
  const Polygon light = Rect(-1, -1, 1, 1);
  const glm::dvec3 p(0.0, 0.0, 0.5);
  // A wall through p facing +x: the light's half x < 0 is behind it.
  EXPECT_TRUE(std::isnan(
      ExactHiddenFraction(light, {}, p, LightWeighting::kIrradiance, glm::dvec3(1, 0, 0))));
  EXPECT_FALSE(
      std::isnan(ExactHiddenFraction(light, {}, p, LightWeighting::kEmitter, glm::dvec3(1, 0, 0))));
}

TEST(ExactWeightedTest, ExactAttenuationTakesTheNormalInWorldSpace) {
  // HalfPlaneScene's light looks down -y onto points at y = 0, whose floor faces +y. The scene
  // path (world normal, turned into light space) equals ExactHiddenFraction in light space.
  const Scene scene = HalfPlaneScene(LightShape::kRect);
  const LightFrame& frame = scene.light.frame;
  Tris tris;
  const TriangleMesh& caster = scene.meshes[0];
  for (uint32_t index : caster.indices) {
    tris.push_back(frame.LightFromWorld(caster.positions_world[index]));
  }
  const std::vector<glm::dvec3> points = {{0.5, 0, 0.3}, {-0.3, 2, 0.1}};
  const glm::dvec3 up(0, 1, 0);
  WeightingSpec spec{LightWeighting::kIrradiance, up};
  absl::StatusOr<std::vector<double>> world = ExactAttenuation(scene, points, spec);
  ASSERT_TRUE(world.ok()) << world.status();
  const glm::dvec3 normal_light = spec.NormalInLightSpace(frame);
  EXPECT_NEAR(normal_light.z, -1.0, 1e-15);  // facing the light: towards light space's -z
  for (size_t i = 0; i < points.size(); ++i) {
    const double light_space =
        ExactHiddenFraction(Rect(-1, -1, 1, 1), tris, frame.LightFromWorld(points[i]),
                            LightWeighting::kIrradiance, normal_light);
    EXPECT_GT(light_space, 0.0) << i;
    EXPECT_LT(light_space, 1.0) << i;
    EXPECT_NEAR((*world)[i], light_space, 1e-12) << i;
  }
  spec.normal_world = -up;  // facing away from the light: nothing measured
  world = ExactAttenuation(scene, points, spec);
  ASSERT_TRUE(world.ok()) << world.status();
  EXPECT_TRUE(std::isnan((*world)[0]));
}

}  // namespace
}  // namespace pdsm
