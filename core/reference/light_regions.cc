#include "core/reference/light_regions.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <utility>

#include "core/reference/polygon_clip.h"

namespace pdsm::internal {
namespace {

// Relative to the light's extent: vertices this close to a neighbour or to the line through
// their neighbours are dropped, and edges this close to one line are coincident. Far above
// rounding noise (1e-16), far below detail that matters; each use moves the hidden area by
// at most this times an edge length.
constexpr double kTolerance = 1e-10;

// Convex (and simple) iff every turn is a left turn and they add up to one full turn.
bool IsConvexCcw(const std::vector<glm::dvec2>& poly) {
  const size_t n = poly.size();
  double turning = 0.0;
  for (size_t i = 0; i < n; ++i) {
    const glm::dvec2 e0 = poly[(i + 1) % n] - poly[i];
    const glm::dvec2 e1 = poly[(i + 2) % n] - poly[(i + 1) % n];
    const double cross = Cross(e0, e1);
    if (cross < 0.0) return false;
    turning += std::atan2(cross, glm::dot(e0, e1));
  }
  return std::abs(turning - 2.0 * std::numbers::pi) < 1e-6;
}

bool InTriangle(const glm::dvec2& q, const glm::dvec2& a, const glm::dvec2& b,
                const glm::dvec2& c) {
  return Cross(b - a, q - a) >= 0.0 && Cross(c - b, q - b) >= 0.0 && Cross(a - c, q - c) >= 0.0;
}

Region MakeRegion(std::vector<glm::dvec2> ccw) {
  Region region;
  region.ccw = std::move(ccw);
  region.area = 0.5 * TwiceSignedArea(region.ccw);
  region.lo = region.hi = region.ccw[0];
  glm::dvec2 sum(0.0);
  for (const glm::dvec2& q : region.ccw) {
    region.lo = glm::min(region.lo, q);
    region.hi = glm::max(region.hi, q);
    sum += q;
  }
  region.inner_center = sum / static_cast<double>(region.ccw.size());
  double radius = std::numeric_limits<double>::infinity();
  const size_t n = region.ccw.size();
  for (size_t i = 0; i < n; ++i) {
    const glm::dvec2 e = region.ccw[(i + 1) % n] - region.ccw[i];
    radius = std::min(radius, Cross(e, region.inner_center - region.ccw[i]) / glm::length(e));
  }
  // Shrunk a little so that rounding in the distance test never skips a needed clip.
  region.inner_radius = std::max(0.0, radius * (1.0 - 1e-9));
  return region;
}

// Ear clipping of a simple counter-clockwise polygon. O(n^2): lights have few vertices.
std::vector<Region> Triangulate(std::vector<glm::dvec2> poly) {
  std::vector<Region> triangles;
  while (poly.size() > 3) {
    const size_t n = poly.size();
    bool clipped = false;
    for (size_t i = 0; i < n && !clipped; ++i) {
      const glm::dvec2& a = poly[(i + n - 1) % n];
      const glm::dvec2& b = poly[i];
      const glm::dvec2& c = poly[(i + 1) % n];
      const double turn = Cross(b - a, c - b);
      if (turn == 0.0) {  // collinear: drop the vertex, no triangle
        poly.erase(poly.begin() + i);
        clipped = true;
        break;
      }
      if (turn < 0.0) continue;
      bool ear = true;
      for (size_t k = 0; k < n && ear; ++k) {
        const glm::dvec2& q = poly[k];
        if (q == a || q == b || q == c) continue;
        ear = !InTriangle(q, a, b, c);
      }
      if (!ear) continue;
      triangles.push_back(MakeRegion({a, b, c}));
      poly.erase(poly.begin() + i);
      clipped = true;
    }
    if (!clipped) break;  // not simple; what is left is dropped
  }
  if (poly.size() == 3 && TwiceSignedArea(poly) > 0.0) triangles.push_back(MakeRegion(poly));
  return triangles;
}

}  // namespace

std::optional<PreparedLight> PrepareLight(std::span<const glm::dvec2> polygon) {
  std::vector<glm::dvec2> ccw(polygon.begin(), polygon.end());
  for (const glm::dvec2& q : ccw) {
    if (!std::isfinite(q.x) || !std::isfinite(q.y)) return std::nullopt;
  }
  if (ccw.size() < 3) return std::nullopt;
  if (TwiceSignedArea(ccw) < 0.0) std::reverse(ccw.begin(), ccw.end());
  PreparedLight light;
  light.lo = light.hi = ccw[0];
  for (const glm::dvec2& q : ccw) {
    light.lo = glm::min(light.lo, q);
    light.hi = glm::max(light.hi, q);
  }
  light.tolerance = kTolerance * std::max(light.hi.x - light.lo.x, light.hi.y - light.lo.y);
  RemoveNearlyCollinear(light.tolerance, &ccw);
  if (ccw.size() < 3) return std::nullopt;
  light.area = 0.5 * TwiceSignedArea(ccw);
  if (!(light.area > 0.0)) return std::nullopt;
  if (IsConvexCcw(ccw)) {
    light.regions.push_back(MakeRegion(std::move(ccw)));
  } else {
    light.regions = Triangulate(std::move(ccw));
  }
  return light;
}

}  // namespace pdsm::internal
