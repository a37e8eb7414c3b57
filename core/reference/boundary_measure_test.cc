// The three boundary measures against brute-force quadrature over the region (an independent
// computation: no boundary, no formula shared), and the property the union relies on: a
// segment's term is the sum of its parts' terms.
#include "core/reference/boundary_measure.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace pdsm::internal {
namespace {

struct Integrals {
  double area = 0.0, solid_angle = 0.0, projected = 0.0;
};

// Midpoint rule over the rectangle [x0, x1] x [y0, y1] of the plane z = 0, seen from p.
Integrals Quadrature(double x0, double y0, double x1, double y1, const glm::dvec3& p,
                     const glm::dvec3& normal, int n) {
  Integrals sum;
  const double dx = (x1 - x0) / n, dy = (y1 - y0) / n;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      const glm::dvec3 q(x0 + (i + 0.5) * dx, y0 + (j + 0.5) * dy, 0.0);
      const glm::dvec3 d = q - p;
      const double r = glm::length(d);
      const double cos_light = p.z / r;  // the plane's normal is z
      const double d_omega = cos_light / (r * r) * dx * dy;
      sum.area += dx * dy;
      sum.solid_angle += d_omega;
      sum.projected += glm::dot(normal, d) / r * d_omega;
    }
  }
  return sum;
}

std::vector<glm::dvec2> RectCcw(double x0, double y0, double x1, double y1) {
  return {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
}

TEST(BoundaryMeasure, EachMeasureOfARectangleMatchesQuadrature) {
  // Seen from points above it, beside it and far off; the receiver tilted.
  const glm::dvec3 normal = glm::normalize(glm::dvec3(0.2, -0.1, -1.0));
  for (const glm::dvec3& p :
       {glm::dvec3(0.4, 0.3, 2.0), glm::dvec3(3.0, -1.0, 2.0), glm::dvec3(-6.0, 9.0, 30.0)}) {
    const auto rect = RectCcw(-1.0, -0.5, 2.0, 1.5);
    const Integrals q = Quadrature(-1.0, -0.5, 2.0, 1.5, p, normal, 1500);
    const double area = BoundaryMeasure::Area().Polygon(rect);
    const double omega = BoundaryMeasure::SolidAngle(p).Polygon(rect);
    const double projected = BoundaryMeasure::ProjectedSolidAngle(p, normal).Polygon(rect);
    EXPECT_NEAR(area, 6.0, 1e-12);
    EXPECT_NEAR(omega / q.solid_angle, 1.0, 1e-6) << p.x;
    EXPECT_NEAR(projected / q.projected, 1.0, 1e-6) << p.x;
    EXPECT_GT(omega, 0.0);
    EXPECT_GT(projected, 0.0);
  }
}

TEST(BoundaryMeasure, AClockwiseBoundaryGivesTheNegativeAndTheOriginDoesNotMatter) {
  const glm::dvec3 p(0.7, -2.0, 1.5);
  const glm::dvec3 normal = glm::normalize(glm::dvec3(0.3, 0.4, -1.0));
  const std::vector<glm::dvec2> ccw = {{0.0, 0.0}, {2.0, 0.5}, {1.0, 2.0}};
  const std::vector<glm::dvec2> cw = {{0.0, 0.0}, {1.0, 2.0}, {2.0, 0.5}};
  // The same triangle split into three around an inner point.
  const glm::dvec2 m(1.0, 0.8);
  for (const BoundaryMeasure& measure : {BoundaryMeasure::Area(), BoundaryMeasure::SolidAngle(p),
                                         BoundaryMeasure::ProjectedSolidAngle(p, normal)}) {
    const double whole = measure.Polygon(ccw);
    EXPECT_NEAR(measure.Polygon(cw), -whole, 1e-15);
    double parts = 0.0;
    for (size_t k = 0; k < 3; ++k) {
      const std::vector<glm::dvec2> fan = {ccw[k], ccw[(k + 1) % 3], m};
      parts += measure.Polygon(fan);
    }
    EXPECT_NEAR(parts, whole, 1e-14 * std::abs(whole));
  }
}

TEST(BoundaryMeasure, ASegmentsTermIsTheSumOfItsParts) {
  const glm::dvec3 p(0.2, 0.1, 0.8);
  const glm::dvec3 normal = glm::normalize(glm::dvec3(-0.1, 0.2, -1.0));
  const glm::dvec2 s(-3.0, 0.5), t(4.0, -1.5);
  for (const BoundaryMeasure& measure : {BoundaryMeasure::Area(), BoundaryMeasure::SolidAngle(p),
                                         BoundaryMeasure::ProjectedSolidAngle(p, normal)}) {
    double parts = 0.0;
    glm::dvec2 from = s;
    for (double f : {0.1, 0.35, 0.5, 0.9, 1.0}) {
      const glm::dvec2 to = f == 1.0 ? t : s + f * (t - s);
      parts += measure.Segment(from, to);
      from = to;
    }
    EXPECT_NEAR(parts, measure.Segment(s, t), 1e-14);
  }
}

// A tiny triangle far away: the solid angle is area cos / r^2 to first order, and atan2 keeps
// its digits (no cancellation of two near-equal angles).
TEST(BoundaryMeasure, ATinyFarTriangleKeepsItsPrecision) {
  const glm::dvec3 p(0.0, 0.0, 1e3);
  const std::vector<glm::dvec2> tiny = {{5.0, 5.0}, {5.0 + 1e-4, 5.0}, {5.0, 5.0 + 1e-4}};
  const double area = 0.5e-8;
  const glm::dvec3 d = glm::dvec3(5.0, 5.0, 0.0) - p;
  const double r = glm::length(d);
  const double expected = area * (p.z / r) / (r * r);
  EXPECT_NEAR(BoundaryMeasure::SolidAngle(p).Polygon(tiny) / expected, 1.0, 1e-4);
}

}  // namespace
}  // namespace pdsm::internal
