#include "core/bake/tile_reach.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "core/bake/face_samples.h"

namespace pdsm {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Extent of a rectangle's ray origins: its pixel centres in window coordinates.
struct TileSpan {
  double s_lo, s_hi, t_lo, t_hi;
};

TileSpan SpanOf(const PdsmGeometry& g, const TileRect& tile) {
  return {g.PixelCenterS(tile.x0), g.PixelCenterS(tile.x0 + tile.width - 1),
          g.PixelCenterT(tile.y0), g.PixelCenterT(tile.y0 + tile.height - 1)};
}

// The samples' extent on each axis, widened to hold 0: the bounds below use min(0, a) and
// max(0, a) over the samples.
struct SampleExtent {
  glm::dvec2 neg, pos;
};

SampleExtent ExtentOf(const BakePlan& plan) {
  glm::dvec2 lo(kInf), hi(-kInf);
  for (const glm::dvec2& sample : plan.samples) {
    lo = glm::min(lo, sample);
    hi = glm::max(hi, sample);
  }
  // A sphere face's groups stretch the samples (core/bake/face_samples.h).
  const double stretch = FaceSampleStretch(plan);
  return {stretch * glm::min(lo, glm::dvec2(0.0)), stretch * glm::max(hi, glm::dvec2(0.0))};
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
  const SampleExtent e = ExtentOf(plan);
  const glm::dvec2 neg = e.neg, pos = e.pos;
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

// The nearest depth at which a point of the convex hull of `points` (a triangle's 3 vertices,
// a box's 8 corners) can shadow a ray of `span` (docs/algorithms.md). With
// g_hi = x_P - s_hi z_P > 0, a perspective shadow needs a (1 - l) >= g_hi, so
// l <= 1 - g_hi / max(a) and z_Q = z_P / l >= z_P / (1 - g_hi / max(a)); the sun needs
// z_Q - z_P >= g_hi / max(-a). Each g is linear, so its minimum over the hull is at a
// vertex; the largest of the four bounds holds. +infinity: the hull cannot shadow. The result
// only grows as the hull shrinks (each minimum grows), so a box's is a bound of its triangles'.
// `margin` > 0 (boxes): every g is lowered by that fraction of its terms' magnitude, and f by
// that much, so the result is a lower bound of every triangle inside even where their own
// evaluation rounds differently (and +infinity only where none of them can shadow).
double NearestShadowedDepth(const BakePlan& plan, const SampleExtent& e, const TileSpan& span,
                            const glm::dvec3* points, int count, double margin = 0) {
  const bool sun = plan.geometry().projection == Projection::kOrthographic;
  double g_min[4] = {kInf, kInf, kInf, kInf};
  double z_min = kInf;
  double scale = 0;
  for (int k = 0; k < count; ++k) {
    const glm::dvec3& p = points[k];
    const double zs = sun ? 1.0 : p.z;  // perspective measures offsets at the point's depth
    g_min[0] = std::min(g_min[0], p.x - span.s_hi * zs);
    g_min[1] = std::min(g_min[1], span.s_lo * zs - p.x);
    g_min[2] = std::min(g_min[2], p.y - span.t_hi * zs);
    g_min[3] = std::min(g_min[3], span.t_lo * zs - p.y);
    z_min = std::min(z_min, p.z);
    if (margin > 0) {
      scale = std::max({scale, std::abs(p.x) + std::abs(span.s_hi * zs) + std::abs(span.s_lo * zs),
                        std::abs(p.y) + std::abs(span.t_hi * zs) + std::abs(span.t_lo * zs)});
    }
  }
  for (double& g : g_min) g -= margin * scale;
  // The sample reach that offsets each side: x beyond s_hi needs a > 0 (perspective) or
  // a < 0 (sun), and so on.
  const double reach[4] = {sun ? -e.neg.x : e.pos.x, sun ? e.pos.x : -e.neg.x,
                           sun ? -e.neg.y : e.pos.y, sun ? e.pos.y : -e.neg.y};
  double f = 0;
  for (int k = 0; k < 4; ++k) {
    if (g_min[k] <= 0) continue;
    if (!(reach[k] > 0)) return kInf;
    f = std::max(f, g_min[k] / reach[k]);
  }
  f = std::max(0.0, f - margin);
  // Only the part at z >= z_clip_near is drawn into shadow maps.
  z_min = std::max(z_min, plan.z_clip_near);
  if (sun) return z_min + f;
  if (f >= 1.0) return kInf;
  return z_min / (1.0 - f);
}

// The tile cut into blocks of kRayBlockSize pixels, row-major.
std::vector<TileRect> BlocksOf(const TileRect& tile) {
  std::vector<TileRect> blocks;
  for (int y = tile.y0; y < tile.y0 + tile.height; y += kRayBlockSize) {
    for (int x = tile.x0; x < tile.x0 + tile.width; x += kRayBlockSize) {
      TileRect block;
      block.x0 = x;
      block.y0 = y;
      block.width = std::min(kRayBlockSize, tile.x0 + tile.width - x);
      block.height = std::min(kRayBlockSize, tile.y0 + tile.height - y);
      blocks.push_back(block);
    }
  }
  return blocks;
}

// Triangle k of `mesh` in double, and whether it lies wholly outside one of `region`'s
// half-spaces (then it cannot shadow the tile's rays).
// A window side in texels as an int, saturated: a wider window than int holds stays too big
// for the texel budget instead of wrapping negative and slipping past it.
int SaturatedExtent(int64_t texels) {
  return static_cast<int>(std::min<int64_t>(texels, std::numeric_limits<int>::max()));
}

std::array<glm::dvec3, 3> CasterTriangle(const LightSpaceMesh& mesh, size_t k) {
  return {glm::dvec3(mesh.positions[mesh.indices[3 * k]]),
          glm::dvec3(mesh.positions[mesh.indices[3 * k + 1]]),
          glm::dvec3(mesh.positions[mesh.indices[3 * k + 2]])};
}

bool OutsideRegion(const std::vector<HalfSpace>& region, const std::array<glm::dvec3, 3>& p) {
  return std::any_of(region.begin(), region.end(),
                     [&](const HalfSpace& h) { return h(p[0]) > 0 && h(p[1]) > 0 && h(p[2]) > 0; });
}

std::array<glm::dvec3, 8> Corners(const glm::dvec3& lo, const glm::dvec3& hi) {
  std::array<glm::dvec3, 8> corners;
  for (int k = 0; k < 8; ++k) {
    corners[k] = {(k & 1) ? hi.x : lo.x, (k & 2) ? hi.y : lo.y, (k & 4) ? hi.z : lo.z};
  }
  return corners;
}

// Whether the whole box lies outside one half-space, so that no triangle inside it can shadow
// the rays. A linear function's minimum over a box is at a corner; the margin (far above the
// dot products' rounding) keeps the test from dropping a triangle that the per-triangle test
// keeps: clusters only save work, the triangles kept are the same.
bool BoxOutsideRegion(const std::vector<HalfSpace>& region, const glm::dvec3& lo,
                      const glm::dvec3& hi) {
  const std::array<glm::dvec3, 8> corners = Corners(lo, hi);
  return std::any_of(region.begin(), region.end(), [&](const HalfSpace& h) {
    return std::all_of(corners.begin(), corners.end(), [&](const glm::dvec3& p) {
      const double scale = glm::dot(glm::abs(h.coef), glm::abs(p)) + std::abs(h.constant);
      return h(p) > 1e-12 * scale;
    });
  });
}

// NearestShadowedDepth's lower bound over every triangle inside the box, lowered by a relative
// margin far above rounding: skipping a box whose bound does not beat the best so far never
// skips a triangle that would.
double NearestShadowedDepthOfBox(const BakePlan& plan, const SampleExtent& e, const TileSpan& span,
                                 const glm::dvec3& lo, const glm::dvec3& hi) {
  const std::array<glm::dvec3, 8> corners = Corners(lo, hi);
  const double z = NearestShadowedDepth(plan, e, span, corners.data(), 8, /*margin=*/1e-12);
  return std::isfinite(z) ? z - 1e-9 * std::abs(z) : z;
}

// The kept triangles of a tile (in the casters' order), grouped by the cluster they came from,
// each group with the bounding box of its kept triangles.
struct KeptTriangles {
  std::vector<uint32_t> triangles;
  std::vector<glm::dvec3> vertices;  // 3 per kept triangle
  struct Group {
    uint32_t begin, end;  // into triangles
    glm::dvec3 lo, hi;
  };
  std::vector<Group> groups;
};

// The triangles of the casters not wholly outside one of the region's half-spaces, tested
// cluster by cluster; `first_only` stops at the first one.
KeptTriangles KeepInside(const BakePlan& plan, const std::vector<HalfSpace>& region,
                         bool first_only) {
  KeptTriangles out;
  for (const CasterCluster& c : plan.caster_clusters) {
    if (BoxOutsideRegion(region, c.lo, c.hi)) continue;
    KeptTriangles::Group group{static_cast<uint32_t>(out.triangles.size()), 0, glm::dvec3(kInf),
                               glm::dvec3(-kInf)};
    for (uint32_t k = c.first_triangle; k < c.first_triangle + c.triangle_count; ++k) {
      const std::array<glm::dvec3, 3> p = CasterTriangle(plan.casters, k);
      if (OutsideRegion(region, p)) continue;
      out.triangles.push_back(k);
      for (const glm::dvec3& v : p) {
        out.vertices.push_back(v);
        group.lo = glm::min(group.lo, v);
        group.hi = glm::max(group.hi, v);
      }
      if (first_only) return out;
    }
    group.end = static_cast<uint32_t>(out.triangles.size());
    if (group.end > group.begin) out.groups.push_back(group);
  }
  return out;
}

// A half-space bounded below over several: at a point p, each coefficient is the least of
// theirs where p's coordinate is >= 0 and the greatest elsewhere, and the constant the least.
// The bound is the least of the linear functions over that box of coefficients, concave in p:
// over a box of points it is least at a corner.
struct HalfSpaceLowerBound {
  glm::dvec3 coef_lo{kInf}, coef_hi{-kInf};
  double constant_lo = kInf;

  void Add(const HalfSpace& h) {
    coef_lo = glm::min(coef_lo, h.coef);
    coef_hi = glm::max(coef_hi, h.coef);
    constant_lo = std::min(constant_lo, h.constant);
  }
  // Evaluated as HalfSpace::operator() is (the same dot product, then the constant), so that
  // each rounded step is no greater than the same step of any half-space bounded.
  double operator()(const glm::dvec3& p) const {
    const glm::dvec3 coef(p.x >= 0 ? coef_lo.x : coef_hi.x, p.y >= 0 ? coef_lo.y : coef_hi.y,
                          p.z >= 0 ? coef_lo.z : coef_hi.z);
    return glm::dot(coef, p) + constant_lo;
  }
  // Whether the bound is above a margin far over rounding at p: 1e-12 of the size of its terms
  // at any point within `extent` of the origin on each axis.
  bool Above(const glm::dvec3& p, const glm::dvec3& extent) const {
    const glm::dvec3 coef_size = glm::max(glm::abs(coef_lo), glm::abs(coef_hi));
    return (*this)(p) > 1e-12 * (glm::dot(coef_size, extent) + std::abs(constant_lo));
  }
  // Whether every point of the box [lo, hi] is above the bound, by that margin: the bound's
  // least over the box is at a corner, and the margin holds for the whole box.
  bool BoxAbove(const glm::dvec3& lo, const glm::dvec3& hi) const {
    const glm::dvec3 extent = glm::max(glm::abs(lo), glm::abs(hi));
    const std::array<glm::dvec3, 8> corners = Corners(lo, hi);
    return std::all_of(corners.begin(), corners.end(),
                       [&](const glm::dvec3& p) { return Above(p, extent); });
  }
};

}  // namespace

struct CasterReachBound::Bounds {
  std::vector<HalfSpaceLowerBound> bounds;
};

CasterReachBound::CasterReachBound(const BakePlan& plan) {
  auto bounds = std::make_shared<Bounds>();
  for (int i = 0; i < plan.tile_count(); ++i) {
    const std::vector<HalfSpace> region =
        ShadowingRegion(plan, SpanOf(plan.geometry(), plan.tile(i)));
    bounds->bounds.resize(region.size());
    for (size_t k = 0; k < region.size(); ++k) bounds->bounds[k].Add(region[k]);
  }
  bounds_ = std::move(bounds);
  none_ = plan.tile_count() == 0;
}

bool CasterReachBound::BoxMayReach(const glm::dvec3& lo, const glm::dvec3& hi) const {
  if (none_) return false;
  return std::none_of(bounds_->bounds.begin(), bounds_->bounds.end(),
                      [&](const HalfSpaceLowerBound& b) { return b.BoxAbove(lo, hi); });
}

bool CasterReachBound::TriangleMayReach(const std::array<glm::dvec3, 3>& p) const {
  if (none_) return false;
  return std::none_of(bounds_->bounds.begin(), bounds_->bounds.end(),
                      [&](const HalfSpaceLowerBound& b) {
                        return b.Above(p[0], glm::abs(p[0])) && b.Above(p[1], glm::abs(p[1])) &&
                               b.Above(p[2], glm::abs(p[2]));
                      });
}

bool TileHasCasters(const BakePlan& plan, const TileRect& tile) {
  const std::vector<HalfSpace> region = ShadowingRegion(plan, SpanOf(plan.geometry(), tile));
  return !KeepInside(plan, region, /*first_only=*/true).triangles.empty();
}

TileReach ComputeTileReach(const BakePlan& plan, const TileRect& tile) {
  TileReach reach;
  reach.z_near = kInf;
  const PdsmGeometry& g = plan.geometry();
  const std::vector<HalfSpace> region = ShadowingRegion(plan, SpanOf(g, tile));
  KeptTriangles kept = KeepInside(plan, region, /*first_only=*/false);
  reach.triangles = std::move(kept.triangles);
  if (reach.triangles.empty()) return reach;

  // Per block of rays: the nearest depth any kept triangle can shadow them from. The block's
  // span is widened by one shadow-map texel: a texel holds the depth seen at its centre, up to
  // half a texel from where the ray crosses it.
  const SampleExtent extent = ExtentOf(plan);
  std::vector<std::pair<double, size_t>> bounds;  // (box bound, group), per block
  const double z_last = g.projection == Projection::kOrthographic ? plan.z_clip_far : kInf;
  for (const TileRect& block : BlocksOf(tile)) {
    TileSpan span = SpanOf(g, block);
    span.s_lo -= plan.lattice.pitch_s;
    span.s_hi += plan.lattice.pitch_s;
    span.t_lo -= plan.lattice.pitch_t;
    span.t_hi += plan.lattice.pitch_t;
    // The minimum over the kept triangles, a cluster's at a time, nearest bound first: once a
    // cluster's box cannot beat the best so far, no later one can.
    bounds.clear();
    for (size_t i = 0; i < kept.groups.size(); ++i) {
      const KeptTriangles::Group& group = kept.groups[i];
      bounds.emplace_back(NearestShadowedDepthOfBox(plan, extent, span, group.lo, group.hi), i);
    }
    std::sort(bounds.begin(), bounds.end());
    double z_begin = kInf;
    for (const auto& [bound, i] : bounds) {
      if (!(bound < z_begin)) break;
      const KeptTriangles::Group& group = kept.groups[i];
      for (uint32_t t = group.begin; t < group.end; ++t) {
        z_begin =
            std::min(z_begin, NearestShadowedDepth(plan, extent, span, &kept.vertices[3 * t], 3));
      }
    }
    // No caster can shadow these rays (before the sun's rays end): all lit.
    if (std::isinf(z_begin) || z_begin > z_last) continue;
    z_begin = std::max({z_begin, plan.z_clip_near, plan.z_scan_floor});
    reach.blocks.push_back(RayBlock{block, z_begin});
    reach.z_near = std::min(reach.z_near, z_begin);
  }
  return reach;
}

bool DrawnDepths(const BakePlan& plan, double box_lo_z, double box_hi_z, double* z_lo,
                 double* z_hi) {
  const bool sun = plan.geometry().projection == Projection::kOrthographic;
  *z_lo = std::max(box_lo_z, plan.z_clip_near);
  *z_hi = sun ? std::min(box_hi_z, plan.z_clip_far) : box_hi_z;
  return *z_lo <= *z_hi;
}

std::vector<bool> TilesCastersMayReach(const BakePlan& plan, std::span<const CasterBox> boxes,
                                       const TriangleBoxes& triangle_boxes) {
  std::vector<bool> reached(plan.tile_count(), false);
  const PdsmGeometry& g = plan.geometry();
  const bool sun = g.projection == Projection::kOrthographic;
  const SampleExtent e = ExtentOf(plan);
  // The tiles whose rays the points of the light-space box [lo, hi] can shadow; false when none.
  const auto tiles_of = [&](const glm::dvec3& lo, const glm::dvec3& hi, int64_t* tx0, int64_t* tx1,
                            int64_t* ty0, int64_t* ty1) {
    double z_lo, z_hi;
    if (!DrawnDepths(plan, lo.z, hi.z, &z_lo, &z_hi)) return false;
    // The rays' (s, t) the box's points can shadow: perspective s = (x - a (1 - l)) / z over
    // a (1 - l) in [min(0, a), max(0, a)]; sun s = x + a (z_q - z), z_q - z in [0, z_far - z].
    double s_lo = kInf, s_hi = -kInf, t_lo = kInf, t_hi = -kInf;
    for (int k = 0; k < 8; ++k) {
      const double x = (k & 1) ? hi.x : lo.x, y = (k & 2) ? hi.y : lo.y;
      const double z = (k & 4) ? z_hi : z_lo;
      if (sun) {
        const double run = std::max(0.0, g.z_far - z);
        s_lo = std::min(s_lo, x + e.neg.x * run), s_hi = std::max(s_hi, x + e.pos.x * run);
        t_lo = std::min(t_lo, y + e.neg.y * run), t_hi = std::max(t_hi, y + e.pos.y * run);
      } else {
        s_lo = std::min(s_lo, (x - e.pos.x) / z), s_hi = std::max(s_hi, (x - e.neg.x) / z);
        t_lo = std::min(t_lo, (y - e.pos.y) / z), t_hi = std::max(t_hi, (y - e.neg.y) / z);
      }
    }
    // Pixel centres within [lo, hi], a pixel wider each side, as tiles.
    const auto pixel = [](double v, double min, double pitch) {
      return static_cast<int64_t>(std::floor((v - min) / pitch - 0.5));
    };
    const int64_t x0 = std::max<int64_t>(0, pixel(s_lo, g.s_min, g.PixelPitchS()) - 1);
    const int64_t x1 = std::min<int64_t>(g.width - 1, pixel(s_hi, g.s_min, g.PixelPitchS()) + 2);
    const int64_t y0 = std::max<int64_t>(0, pixel(t_lo, g.t_min, g.PixelPitchT()) - 1);
    const int64_t y1 = std::min<int64_t>(g.height - 1, pixel(t_hi, g.t_min, g.PixelPitchT()) + 2);
    if (x0 > x1 || y0 > y1) return false;
    const int size = plan.header.tile_size;
    *tx0 = x0 / size, *tx1 = x1 / size, *ty0 = y0 / size, *ty1 = y1 / size;
    return true;
  };
  const auto mark = [&](int64_t tx0, int64_t tx1, int64_t ty0, int64_t ty1) {
    for (int64_t ty = ty0; ty <= ty1; ++ty) {
      for (int64_t tx = tx0; tx <= tx1; ++tx) reached[ty * plan.tiles_x + tx] = true;
    }
  };
  std::vector<std::pair<glm::dvec3, glm::dvec3>> triangles;
  for (size_t i = 0; i < boxes.size(); ++i) {
    const CasterBox& c = boxes[i];
    int64_t tx0, tx1, ty0, ty1;
    if (!tiles_of(c.lo, c.hi, &tx0, &tx1, &ty0, &ty1)) continue;
    // A cluster's box is a coarse bound: 128 roofs scattered over a sparse world have one box
    // over most of it, and every tile under it cost a task that found no caster (32768^2:
    // 258,141 of 262,144 tiles). Where the box spans more tiles than the cluster has
    // triangles, each triangle's own box says which tiles it reaches: within the cluster's,
    // so as conservative.
    if (!triangle_boxes || (tx1 - tx0 + 1) * (ty1 - ty0 + 1) <= int64_t{c.triangle_count}) {
      mark(tx0, tx1, ty0, ty1);
      continue;
    }
    triangles.clear();
    triangle_boxes(i, &triangles);
    for (const auto& [lo, hi] : triangles) {
      if (tiles_of(lo, hi, &tx0, &tx1, &ty0, &ty1)) mark(tx0, tx1, ty0, ty1);
    }
  }
  return reached;
}

RayInShadowMap RayForSample(const BakePlan& plan, double s, double t, const glm::dvec2& sample,
                            double z_near, double z_far) {
  const PdsmGeometry& g = plan.geometry();
  RayInShadowMap ray;
  ray.z_near = z_near;
  if (g.projection == Projection::kPerspective) {
    ray.z_far = z_far > 0 ? std::max(z_far, z_near) : kInf;
    const double w_max = 1.0 / z_near;
    const double w_min = std::isinf(ray.z_far) ? 0.0 : 1.0 / ray.z_far;
    ray.st_near = {s - sample.x * w_max, t - sample.y * w_max};
    ray.st_far = {s - sample.x * w_min, t - sample.y * w_min};
  } else {
    ray.z_far = std::max(z_far > 0 ? z_far : g.z_far, z_near);
    ray.st_near = {s - sample.x * z_near, t - sample.y * z_near};
    ray.st_far = {s - sample.x * ray.z_far, t - sample.y * ray.z_far};
  }
  return ray;
}

ShadowMapWindow ShadowMapWindowFor(const BakePlan& plan, const TileRect& rect,
                                   const glm::dvec2& sample, double z_near, double z_far) {
  const TileSpan span = SpanOf(plan.geometry(), rect);
  const RayInShadowMap lo = RayForSample(plan, span.s_lo, span.t_lo, sample, z_near, z_far);
  const RayInShadowMap hi = RayForSample(plan, span.s_hi, span.t_hi, sample, z_near, z_far);
  const double s_lo = std::min(lo.st_near.x, lo.st_far.x);
  const double t_lo = std::min(lo.st_near.y, lo.st_far.y);
  const double s_hi = std::max(hi.st_near.x, hi.st_far.x);
  const double t_hi = std::max(hi.st_near.y, hi.st_far.y);
  ShadowMapWindow window;
  window.x0 = plan.lattice.TexelS(s_lo);
  window.y0 = plan.lattice.TexelT(t_lo);
  window.width = SaturatedExtent(plan.lattice.TexelS(s_hi) - window.x0 + 1);
  window.height = SaturatedExtent(plan.lattice.TexelT(t_hi) - window.y0 + 1);
  return window;
}

ShadowMapWindow UnionWindow(const ShadowMapWindow& a, const ShadowMapWindow& b) {
  if (a.width <= 0 || a.height <= 0) return b;
  if (b.width <= 0 || b.height <= 0) return a;
  ShadowMapWindow u;
  u.x0 = std::min(a.x0, b.x0);
  u.y0 = std::min(a.y0, b.y0);
  u.width = SaturatedExtent(std::max(a.x0 + a.width, b.x0 + b.width) - u.x0);
  u.height = SaturatedExtent(std::max(a.y0 + a.height, b.y0 + b.height) - u.y0);
  return u;
}

}  // namespace pdsm
