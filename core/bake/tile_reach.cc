#include "core/bake/tile_reach.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace pdsm {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Extent of the tile's ray origins: its pixel centres in window coordinates.
struct TileSpan {
  double s_lo, s_hi, t_lo, t_hi;
};

TileSpan SpanOf(const PdsmGeometry& g, const TileRect& tile) {
  return {g.PixelCenterS(tile.x0), g.PixelCenterS(tile.x0 + tile.width - 1),
          g.PixelCenterT(tile.y0), g.PixelCenterT(tile.y0 + tile.height - 1)};
}

// A linear function f(p) = dot(coef, p) + constant of light-space points; the region that can
// shadow the tile is where every one is <= 0.
struct HalfSpace {
  glm::dvec3 coef;
  double constant;
  double operator()(const glm::dvec3& p) const { return glm::dot(coef, p) + constant; }
};

// The shadowing region's bounding half-spaces (derivation in docs/algorithms.md):
// perspective: a point P shadows ray q from sample (a, b) iff P = S + l (Q - S), which gives
// x_P - s_q z_P = a (1 - l) in [min(0, a), max(0, a)]; sun: x_P - s_q = -a (z_q - z_P).
std::vector<HalfSpace> ShadowingRegion(const BakePlan& plan, const TileSpan& span) {
  glm::dvec2 lo(kInf), hi(-kInf);
  for (const glm::dvec2& sample : plan.samples) {
    lo = glm::min(lo, sample);
    hi = glm::max(hi, sample);
  }
  const glm::dvec2 neg = glm::min(lo, glm::dvec2(0.0));
  const glm::dvec2 pos = glm::max(hi, glm::dvec2(0.0));
  const double slack = 1e-9 * (1.0 + std::max(std::abs(span.s_hi), std::abs(span.t_hi)));
  const PdsmGeometry& g = plan.geometry();
  std::vector<HalfSpace> region;
  region.push_back({{0, 0, -1}, plan.z_clip_near});  // z >= z_clip_near
  if (g.projection == Projection::kPerspective) {
    region.push_back({{1, 0, -(span.s_hi + slack)}, -pos.x});  // x - s_hi z <= max(0, a)
    region.push_back({{-1, 0, span.s_lo - slack}, neg.x});     // x - s_lo z >= min(0, a)
    region.push_back({{0, 1, -(span.t_hi + slack)}, -pos.y});
    region.push_back({{0, -1, span.t_lo - slack}, neg.y});
  } else {
    // x <= s_hi - min(0, a) (z_far - z) and x >= s_lo - max(0, a) (z_far - z).
    region.push_back({{1, 0, -neg.x}, -(span.s_hi + slack) + neg.x * g.z_far});
    region.push_back({{-1, 0, pos.x}, span.s_lo - slack - pos.x * g.z_far});
    region.push_back({{0, 1, -neg.y}, -(span.t_hi + slack) + neg.y * g.z_far});
    region.push_back({{0, -1, pos.y}, span.t_lo - slack - pos.y * g.z_far});
    region.push_back({{0, 0, 1}, -g.z_far});  // z <= z_far
  }
  return region;
}

}  // namespace

TileReach ComputeTileReach(const BakePlan& plan, const TileRect& tile) {
  TileReach reach;
  reach.z_near = kInf;
  const std::vector<HalfSpace> region = ShadowingRegion(plan, SpanOf(plan.geometry(), tile));
  const LightSpaceMesh& mesh = plan.casters;
  for (size_t k = 0; k < mesh.TriangleCount(); ++k) {
    const glm::dvec3 p[3] = {glm::dvec3(mesh.positions[mesh.indices[3 * k]]),
                             glm::dvec3(mesh.positions[mesh.indices[3 * k + 1]]),
                             glm::dvec3(mesh.positions[mesh.indices[3 * k + 2]])};
    const bool outside = std::any_of(region.begin(), region.end(), [&](const HalfSpace& h) {
      return h(p[0]) > 0 && h(p[1]) > 0 && h(p[2]) > 0;
    });
    if (outside) continue;
    reach.triangles.push_back(static_cast<uint32_t>(k));
    reach.z_near = std::min({reach.z_near, p[0].z, p[1].z, p[2].z});
  }
  reach.z_near = std::max(reach.z_near, plan.z_clip_near);
  return reach;
}

RayInShadowMap RayForSample(const BakePlan& plan, double s, double t, const glm::dvec2& sample,
                            double z_near) {
  const PdsmGeometry& g = plan.geometry();
  RayInShadowMap ray;
  ray.z_near = z_near;
  if (g.projection == Projection::kPerspective) {
    const double w_max = 1.0 / z_near;
    ray.st_near = {s - sample.x * w_max, t - sample.y * w_max};
    ray.st_far = {s, t};
    ray.z_far = kInf;
  } else {
    ray.z_far = std::max(g.z_far, z_near);
    ray.st_near = {s - sample.x * z_near, t - sample.y * z_near};
    ray.st_far = {s - sample.x * ray.z_far, t - sample.y * ray.z_far};
  }
  return ray;
}

ShadowMapWindow ShadowMapWindowFor(const BakePlan& plan, const TileRect& tile,
                                   const glm::dvec2& sample, double z_near) {
  const TileSpan span = SpanOf(plan.geometry(), tile);
  const RayInShadowMap lo = RayForSample(plan, span.s_lo, span.t_lo, sample, z_near);
  const RayInShadowMap hi = RayForSample(plan, span.s_hi, span.t_hi, sample, z_near);
  const double s_lo = std::min(lo.st_near.x, lo.st_far.x);
  const double t_lo = std::min(lo.st_near.y, lo.st_far.y);
  const double s_hi = std::max(hi.st_near.x, hi.st_far.x);
  const double t_hi = std::max(hi.st_near.y, hi.st_far.y);
  ShadowMapWindow window;
  window.x0 = plan.lattice.TexelS(s_lo);
  window.y0 = plan.lattice.TexelT(t_lo);
  window.width = static_cast<int>(plan.lattice.TexelS(s_hi) - window.x0 + 1);
  window.height = static_cast<int>(plan.lattice.TexelT(t_hi) - window.y0 + 1);
  return window;
}

}  // namespace pdsm
