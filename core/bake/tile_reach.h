// What one tile's PDSM rays can meet (thesis 3.3): the casters that can shadow any of its
// rays from any light sample, the nearest depth from which each block of its rays can be
// shadowed, and for each sample the window of the global shadow-map lattice that the rays'
// clipped segments cross. Shadow maps rendered for a tile cover only that window and draw
// only those casters.
#ifndef PDSM_CORE_BAKE_TILE_REACH_H_
#define PDSM_CORE_BAKE_TILE_REACH_H_

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "core/bake/bake_plan.h"
#include "core/bake/shadow_map_lattice.h"

namespace pdsm {

// Rays are clipped per block of kRayBlockSize x kRayBlockSize pixels: small enough that a
// caster over one corner of a tile does not make every ray of the tile start near it, large
// enough that the bound costs little next to the scan itself.
inline constexpr int kRayBlockSize = 8;

// A block of a tile's rays and the nearest depth at which any caster of the tile's reach can
// shadow any of them (conservative, shadow-map texel discretisation included). No event of
// these rays is nearer than z_begin.
struct RayBlock {
  TileRect rect;  // absolute PDSM pixels; rect.index is unused
  double z_begin = 0;
};

struct TileReach {
  std::vector<uint32_t> triangles;  // indices of plan.casters triangles (not vertices)
  std::vector<RayBlock> blocks;     // blocks some caster can shadow; the others are all lit
  double z_near = 0;                // min over blocks of z_begin
  bool empty() const { return blocks.empty(); }
};

// Conservative: a triangle is dropped only when it cannot lie between any light sample and any
// point of any of the tile's rays; a block's z_begin is never deeper than a point of its rays
// that some sample sees through a kept triangle (docs/algorithms.md, "What a tile's rays can
// reach"). z_begin is also at least plan.z_scan_floor.
TileReach ComputeTileReach(const BakePlan& plan, const TileRect& tile);

// Whether any caster can shadow any ray of the tile: ComputeTileReach's triangle test alone,
// stopping at the first triangle kept. False: the tile is all lit and needs no shadow map.
bool TileHasCasters(const BakePlan& plan, const TileRect& tile);

// Whether a caster can shadow some tile of a plan: false only where ComputeTileReach and
// TileHasCasters drop it for every tile, so that leaving the false ones out of the plan changes
// no tile's reach (the same triangles in the same order, the same blocks and depths) and so no
// byte of the bake (core/bake/caster_culling.h). Each half-space of a tile's shadowing region is
// bounded below over all the plan's tiles: at a point, each coefficient is the tiles' least or
// greatest, whichever gives the smaller product with the point's coordinate (the rounded dot
// product is monotone in each), and the constant the least. A triangle (or box) is false when
// its three vertices (its eight corners) are outside one such bound by a relative margin far
// above rounding; the bound is concave, so over a box it is least at a corner. It is loose only
// where tiles disagree: for a local light in a world, it keeps what lies between the light and
// its window, and leaves out the world. Made in time linear in tiles; needs the plan's tiles,
// samples, lattice and clip depths, not its casters. Immutable: safe to share between threads.
class CasterReachBound {
 public:
  explicit CasterReachBound(const BakePlan& plan);
  // A light-space box (a cluster's) some point of which may be in reach.
  bool BoxMayReach(const glm::dvec3& lo, const glm::dvec3& hi) const;
  // A light-space triangle, as the plan's casters hold it (float vertices).
  bool TriangleMayReach(const std::array<glm::dvec3, 3>& p) const;

 private:
  struct Bounds;
  std::shared_ptr<const Bounds> bounds_;
  bool none_ = true;  // a plan without tiles reaches nothing
};

// The part [*z_lo, *z_hi] of the depths [box_lo_z, box_hi_z] of a caster box that the plan's
// shadow maps draw: from z_clip_near on, and for the sun up to z_clip_far. False when the
// maps draw none of it.
bool DrawnDepths(const BakePlan& plan, double box_lo_z, double box_hi_z, double* z_lo,
                 double* z_hi);

// For every tile of the plan, whether a caster may shadow it: each cluster's box marks the
// tiles whose rays its points can shadow from some sample, by the same relation as the reach
// (x_P - s z_P = a (1 - l), sun: x_P - s = -a (z - z_P)) over the depths shadow maps draw,
// widened by a pixel: never false where a drawn point of a caster can shadow the tile. Not a
// superset of TileHasCasters, whose per-triangle test also keeps a triangle across the near
// clip plane whose undrawn part alone is in the tile's reach. Time linear in clusters and
// marked tiles: a world of 10^5 tiles and 10^6 triangles costs milliseconds, not a reach per
// tile. The marks depend on the boxes, so PlanBake marks with the scene index's clusters,
// whatever it then leaves out (core/bake/caster_culling.h).
// Light-space boxes of casters (`triangle_count` of them inside each).
struct CasterBox {
  glm::dvec3 lo, hi;
  uint32_t triangle_count = 0;
};
// The light-space boxes of box i's triangles, appended to `out`: asked for where a box spans
// more tiles than it has triangles. Empty: the boxes alone mark.
using TriangleBoxes =
    std::function<void(size_t i, std::vector<std::pair<glm::dvec3, glm::dvec3>>* out)>;
std::vector<bool> TilesCastersMayReach(const BakePlan& plan, std::span<const CasterBox> boxes,
                                       const TriangleBoxes& triangle_boxes);

// A PDSM ray of the tile seen in one sample's shadow map: a straight segment in lattice
// (s, t) coordinates from its nearest to its farthest point (DESIGN.md: linear in w = 1/z for
// perspective lights, in z for the sun), with the depths at its ends.
struct RayInShadowMap {
  glm::dvec2 st_near, st_far;
  double z_near, z_far;  // z_far = +infinity for perspective lights (w = 0)
};

// The ray's segment from z_near to z_far; z_far <= 0 means the ray's natural end: +infinity
// (perspective) or the plan's z_far (sun).
RayInShadowMap RayForSample(const BakePlan& plan, double s, double t, const glm::dvec2& sample,
                            double z_near, double z_far = 0);

// The lattice window holding every ray segment [z_near, z_far] of the pixels of `rect` for
// this sample (z_far as in RayForSample).
ShadowMapWindow ShadowMapWindowFor(const BakePlan& plan, const TileRect& rect,
                                   const glm::dvec2& sample, double z_near, double z_far = 0);

// The smallest window holding both; an empty window (width 0) is the identity.
ShadowMapWindow UnionWindow(const ShadowMapWindow& a, const ShadowMapWindow& b);

}  // namespace pdsm

#endif  // PDSM_CORE_BAKE_TILE_REACH_H_
