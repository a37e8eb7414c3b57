// The hidden area of a light seen from a point, one point at a time: every caster triangle is
// clipped to the part between the light and the point, projected from the point onto the light
// plane, and clipped to each convex region of the light; the hidden area of a region is the
// area of the union of its pieces (union_area.h), and the regions add up.
#include "core/reference/exact_visibility.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <optional>
#include <thread>
#include <utility>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/str_format.h"
#include "core/reference/boundary_measure.h"
#include "core/reference/convex_set.h"
#include "core/reference/light_regions.h"
#include "core/reference/polygon_clip.h"
#include "core/reference/union_area.h"
#include "core/util/work_queue.h"

namespace pdsm {
namespace {

using internal::BoundaryMeasure;
using internal::ClipConvex;
using internal::ConvexSet;
using internal::Cross;
using internal::PreparedLight;
using internal::PrepareLight;
using internal::Region;
using internal::RemoveNearlyCollinear;
using internal::TwiceSignedArea;
using internal::UnionMeasure;
using internal::UnionScratch;

// Geometry within this distance (relative to p.z) below the point's height is ignored: its
// projection runs off to infinity. A consequence, wanted: the surface a point lies on (its
// own receiver, within rounding) never shadows it.
constexpr double kNearPointMargin = 1e-9;
// The disk light's stand-in. Relative area error 1 - sin(2π/n)/(2π/n) = 2.51e-5 for n = 512.
constexpr int kDiskSides = 512;
// Pieces below this share of the light are degenerate (edge-on triangles, clipping slivers).
constexpr double kDegenerateAreaFraction = 1e-14;

bool Finite(const glm::dvec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

// Per-point setup: the point and the wedge from it through the light's bounding box.
struct Projector {
  glm::dvec3 p;
  double z_max;  // clip plane just short of the point
  glm::dvec2 lo, hi;

  // Half-spaces whose intersection (with 0 < z < p.z) projects into [lo, hi]: for z < p.z,
  // proj(V).x >= lo.x  <=>  (V.x - p.x) p.z >= (lo.x - p.x)(p.z - V.z), and likewise.
  double WedgeXLo(const glm::dvec3& v) const {
    return (v.x - p.x) * p.z - (lo.x - p.x) * (p.z - v.z);
  }
  double WedgeXHi(const glm::dvec3& v) const {
    return (hi.x - p.x) * (p.z - v.z) - (v.x - p.x) * p.z;
  }
  double WedgeYLo(const glm::dvec3& v) const {
    return (v.y - p.y) * p.z - (lo.y - p.y) * (p.z - v.z);
  }
  double WedgeYHi(const glm::dvec3& v) const {
    return (hi.y - p.y) * (p.z - v.z) - (v.y - p.y) * p.z;
  }

  // Conservative cull: the triangle misses the light's box if all three vertices are outside
  // the same bounding plane (all are linear, so then the whole triangle is).
  bool Misses(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c) const {
    if (a.z <= 0.0 && b.z <= 0.0 && c.z <= 0.0) return true;
    if (a.z >= z_max && b.z >= z_max && c.z >= z_max) return true;
    auto all_out = [&](double (Projector::*f)(const glm::dvec3&) const) {
      return (this->*f)(a) < 0.0 && (this->*f)(b) < 0.0 && (this->*f)(c) < 0.0;
    };
    return all_out(&Projector::WedgeXLo) || all_out(&Projector::WedgeXHi) ||
           all_out(&Projector::WedgeYLo) || all_out(&Projector::WedgeYHi);
  }

  glm::dvec2 Project(const glm::dvec3& v) const {
    const double scale = p.z / (p.z - v.z);
    const glm::dvec2 q = glm::dvec2(p) + (glm::dvec2(v) - glm::dvec2(p)) * scale;
    // Inside the wedge up to rounding; the clamp keeps rounding from leaving the box.
    return glm::clamp(q, lo, hi);
  }
};

// Reusable buffers, one set per thread.
struct Workspace {
  std::vector<glm::dvec3> poly3, scratch3;
  std::vector<glm::dvec2> poly2, scratch2;
  std::vector<double> values;
  ConvexSet projected;  // the clipped, projected triangles
  ConvexSet pieces;     // those clipped to one region
  UnionScratch union_scratch;
};

// Clips triangle abc to the part between the light and the point that projects into the
// light's box, and projects it: a convex counter-clockwise polygon in ws->poly2. Returns false
// when nothing of positive area is left.
bool ProjectTriangle(const Projector& proj, const glm::dvec3& a, const glm::dvec3& b,
                     const glm::dvec3& c, double min_area, double tolerance, Workspace* ws) {
  std::vector<glm::dvec3>& poly = ws->poly3;
  poly.assign({a, b, c});
  auto clip = [&](auto f, bool strict) {
    ClipConvex(f, strict, &poly, &ws->scratch3, &ws->values);
  };
  clip([](const glm::dvec3& v) { return v.z; }, /*strict=*/true);
  clip([&](const glm::dvec3& v) { return proj.z_max - v.z; }, false);
  clip([&](const glm::dvec3& v) { return proj.WedgeXLo(v); }, false);
  clip([&](const glm::dvec3& v) { return proj.WedgeXHi(v); }, false);
  clip([&](const glm::dvec3& v) { return proj.WedgeYLo(v); }, false);
  clip([&](const glm::dvec3& v) { return proj.WedgeYHi(v); }, false);
  if (poly.size() < 3) return false;
  ws->poly2.clear();
  for (const glm::dvec3& v : poly) ws->poly2.push_back(proj.Project(v));
  RemoveNearlyCollinear(tolerance, &ws->poly2);
  if (ws->poly2.size() < 3) return false;
  const double twice_area = TwiceSignedArea(ws->poly2);
  if (std::abs(twice_area) <= 2.0 * min_area) return false;
  if (twice_area < 0.0) std::reverse(ws->poly2.begin(), ws->poly2.end());
  return true;
}

// Clips the convex counter-clockwise ws->poly2 to a region. Returns twice the area left, 0 if
// nothing of positive area is.
double ClipToRegion(const Region& region, double min_area, double tolerance, Workspace* ws) {
  std::vector<glm::dvec2>& poly = ws->poly2;
  const double r2 = region.inner_radius * region.inner_radius;
  const bool inside = std::all_of(poly.begin(), poly.end(), [&](const glm::dvec2& q) {
    const glm::dvec2 d = q - region.inner_center;
    return glm::dot(d, d) <= r2;
  });
  if (!inside) {
    const size_t n = region.ccw.size();
    for (size_t i = 0; i < n && poly.size() >= 3; ++i) {
      const glm::dvec2 a = region.ccw[i];
      const glm::dvec2 e = region.ccw[(i + 1) % n] - a;
      ClipConvex([&](const glm::dvec2& q) { return Cross(e, q - a); }, false, &poly, &ws->scratch2,
                 &ws->values);
    }
    RemoveNearlyCollinear(tolerance, &poly);
  }
  if (poly.size() < 3) return 0.0;
  const double twice_area = TwiceSignedArea(poly);
  return twice_area > 2.0 * min_area ? twice_area : 0.0;
}

// Clips and projects every triangle into ws->projected.
void ProjectAll(const PreparedLight& light, std::span<const glm::dvec3> tris, const Projector& proj,
                double min_area, Workspace* ws) {
  ws->projected.Clear();
  for (size_t t = 0; t + 2 < tris.size(); t += 3) {
    const glm::dvec3& a = tris[t];
    const glm::dvec3& b = tris[t + 1];
    const glm::dvec3& c = tris[t + 2];
    if (!Finite(a) || !Finite(b) || !Finite(c)) continue;
    if (proj.Misses(a, b, c)) continue;
    if (!ProjectTriangle(proj, a, b, c, min_area, light.tolerance, ws)) continue;
    ws->projected.Add(ws->poly2, TwiceSignedArea(ws->poly2));
  }
}

// The hidden share of the light's measure (boundary_measure.h: its area, or its solid angle or
// projected solid angle from p).
double HiddenFraction(const PreparedLight& light, std::span<const glm::dvec3> triangles,
                      const glm::dvec3& p, const BoundaryMeasure& measure, Workspace* ws) {
  if (!(p.z > 0.0) || !Finite(p)) return 0.0;
  const Projector proj{p, p.z * (1.0 - kNearPointMargin), light.lo, light.hi};
  const double min_area = kDegenerateAreaFraction * light.area;
  ProjectAll(light, triangles, proj, min_area, ws);
  const ConvexSet& projected = ws->projected;
  double hidden = 0.0, whole = 0.0;
  for (const Region& region : light.regions) {
    const double region_measure = measure.is_area() ? region.area : measure.Polygon(region.ccw);
    whole += region_measure;
    ConvexSet& pieces = ws->pieces;
    pieces.Clear();
    bool umbra = false;
    for (size_t i = 0; i < projected.size() && !umbra; ++i) {
      if (glm::any(glm::lessThan(projected.hi[i], region.lo)) ||
          glm::any(glm::greaterThan(projected.lo[i], region.hi))) {
        continue;
      }
      ws->poly2.assign(projected.vertex.begin() + projected.start[i],
                       projected.vertex.begin() + projected.start[i + 1]);
      const double twice_area = ClipToRegion(region, min_area, light.tolerance, ws);
      if (twice_area <= 0.0) continue;
      // A piece as large as its region covers all of it.
      umbra = 0.5 * twice_area >= region.area * (1.0 - 1e-12);
      pieces.Add(ws->poly2, twice_area);
    }
    hidden += umbra ? region_measure
                    : UnionMeasure(pieces, region.lo, region.hi, light.tolerance, measure,
                                   &ws->union_scratch);
  }
  if (measure.is_area()) whole = light.area;  // the prepared sum, as before
  return std::clamp(hidden / whole, 0.0, 1.0);
}

// HiddenFraction in the measure of `weighting` (light_weighting.h); `normal` (light space, unit)
// for irradiance. cos θ_receiver is integrated with its sign, so where part of the light lies
// behind the receiver's plane the point is not measured (NaN) rather than measured wrong.
double WeightedHiddenFraction(const PreparedLight& light, std::span<const glm::dvec2> polygon,
                              std::span<const glm::dvec3> triangles, const glm::dvec3& p,
                              LightWeighting weighting, const glm::dvec3& normal, Workspace* ws) {
  switch (weighting) {
    case LightWeighting::kUnweighted:
      return HiddenFraction(light, triangles, p, BoundaryMeasure::Area(), ws);
    case LightWeighting::kEmitter:
      return HiddenFraction(light, triangles, p, BoundaryMeasure::SolidAngle(p), ws);
    case LightWeighting::kIrradiance:
      for (const glm::dvec2& q : polygon) {
        if (!(glm::dot(normal, glm::dvec3(q, 0.0) - p) > 0.0)) {
          return std::numeric_limits<double>::quiet_NaN();
        }
      }
      return HiddenFraction(light, triangles, p, BoundaryMeasure::ProjectedSolidAngle(p, normal),
                            ws);
  }
  return std::numeric_limits<double>::quiet_NaN();
}

absl::StatusOr<std::vector<glm::dvec2>> LightPolygon(const LightSpec& light) {
  auto positive = [](double x) { return std::isfinite(x) && x > 0.0; };
  switch (light.shape) {
    case LightShape::kRect: {
      if (!positive(light.half_width) || !positive(light.half_height)) {
        return absl::InvalidArgumentError(
            absl::StrFormat("light.rect: size must be positive and finite, got half sizes %g x %g",
                            light.half_width, light.half_height));
      }
      const double w = light.half_width, h = light.half_height;
      return std::vector<glm::dvec2>{{-w, -h}, {w, -h}, {w, h}, {-w, h}};
    }
    case LightShape::kDisk: {
      if (!positive(light.radius)) {
        return absl::InvalidArgumentError(absl::StrFormat(
            "light.disk: radius must be positive and finite, got %g", light.radius));
      }
      // Inscribed regular polygon: the reference is exact for it, and its area is short of
      // the disk's by 2.5e-5 relative, below any bake's sampling error.
      std::vector<glm::dvec2> polygon;
      polygon.reserve(kDiskSides);
      for (int k = 0; k < kDiskSides; ++k) {
        const double angle = 2.0 * std::numbers::pi * k / kDiskSides;
        polygon.emplace_back(light.radius * std::cos(angle), light.radius * std::sin(angle));
      }
      return polygon;
    }
    case LightShape::kSun:
      break;
  }
  return absl::UnimplementedError(
      "exact attenuation supports rect and disk lights only, not sun lights");
}

// All caster triangles in light space, 3 vertices each; those wholly behind the light dropped.
absl::StatusOr<std::vector<glm::dvec3>> CastersInLightSpace(const Scene& scene) {
  const LightFrame& frame = scene.light.frame;
  std::vector<glm::dvec3> triangles;
  for (const TriangleMesh& mesh : scene.meshes) {
    if (!Casts(mesh.role)) continue;
    if (mesh.indices.size() % 3 != 0) {
      return absl::InvalidArgumentError(absl::StrFormat("%s: index count %d is not a multiple of 3",
                                                        mesh.label, mesh.indices.size()));
    }
    for (size_t i = 0; i < mesh.indices.size(); i += 3) {
      glm::dvec3 v[3];
      for (int k = 0; k < 3; ++k) {
        const uint32_t index = mesh.indices[i + k];
        if (index >= mesh.positions_world.size()) {
          return absl::InvalidArgumentError(
              absl::StrFormat("%s: index %d out of range (%d vertices)", mesh.label, index,
                              mesh.positions_world.size()));
        }
        v[k] = frame.LightFromWorld(mesh.positions_world[index]);
      }
      if (v[0].z <= 0.0 && v[1].z <= 0.0 && v[2].z <= 0.0) continue;
      triangles.insert(triangles.end(), {v[0], v[1], v[2]});
    }
  }
  return triangles;
}

}  // namespace

double ExactHiddenFraction(std::span<const glm::dvec2> light_polygon,
                           std::span<const glm::dvec3> triangles, const glm::dvec3& p_light,
                           LightWeighting weighting, const glm::dvec3& normal_light) {
  // A degenerate light has nothing to hide.
  const std::optional<PreparedLight> light = PrepareLight(light_polygon);
  if (!light.has_value()) return 0.0;
  Workspace ws;
  return WeightedHiddenFraction(*light, light_polygon, triangles, p_light, weighting, normal_light,
                                &ws);
}

absl::StatusOr<std::vector<double>> ExactAttenuation(const Scene& scene,
                                                     std::span<const glm::dvec3> points_world,
                                                     const WeightingSpec& weighting) {
  absl::StatusOr<std::vector<glm::dvec2>> polygon = LightPolygon(scene.light);
  if (!polygon.ok()) return polygon.status();
  absl::StatusOr<std::vector<glm::dvec3>> triangles = CastersInLightSpace(scene);
  if (!triangles.ok()) return triangles.status();
  const std::optional<PreparedLight> light = PrepareLight(*polygon);
  if (!light.has_value()) return absl::InternalError("light polygon is degenerate");
  const LightFrame& frame = scene.light.frame;
  const glm::dvec3 normal_light = weighting.NormalInLightSpace(frame);

  std::vector<double> result(points_world.size(), std::numeric_limits<double>::quiet_NaN());
  // Points are independent: threads take them one at a time and each writes only its own
  // slot, so the output does not depend on the scheduling.
  std::atomic<size_t> next{0};
  RunOnAllCores(points_world.size(), [&] {
    Workspace ws;
    for (size_t i = next++; i < points_world.size(); i = next++) {
      const glm::dvec3 p_light = frame.LightFromWorld(points_world[i]);
      if (!(p_light.z > 0.0) || !Finite(p_light)) continue;  // stays NaN
      result[i] = WeightedHiddenFraction(*light, *polygon, *triangles, p_light, weighting.kind,
                                         normal_light, &ws);
    }
  });
  return result;
}

}  // namespace pdsm
