// What one tile's PDSM rays can meet (thesis 3.3): the casters that can shadow any of its
// rays from any light sample, the nearest depth among them, and for each sample the window of
// the global shadow-map lattice that the tile's ray segments cross. Shadow maps rendered for a
// tile cover only that window and draw only those casters.
#ifndef PDSM_CORE_BAKE_TILE_REACH_H_
#define PDSM_CORE_BAKE_TILE_REACH_H_

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "core/bake/bake_plan.h"
#include "core/bake/shadow_map_lattice.h"

namespace pdsm {

struct TileReach {
  std::vector<uint32_t> triangles;  // indices of plan.casters triangles (not vertices)
  double z_near = 0;                // rays are scan-converted from here on
  bool empty() const { return triangles.empty(); }
};

// Conservative: a triangle is dropped only when it cannot lie between any light sample and any
// point of any of the tile's rays.
TileReach ComputeTileReach(const BakePlan& plan, const TileRect& tile);

// A PDSM ray of the tile seen in one sample's shadow map: a straight segment in lattice
// (s, t) coordinates from its nearest to its farthest point (DESIGN.md: linear in w = 1/z for
// perspective lights, in z for the sun), with the depths at its ends.
struct RayInShadowMap {
  glm::dvec2 st_near, st_far;
  double z_near, z_far;  // z_far = +infinity for perspective lights (w = 0)
};

RayInShadowMap RayForSample(const BakePlan& plan, double s, double t, const glm::dvec2& sample,
                            double z_near);

// The lattice window holding every ray segment of the tile for this sample.
ShadowMapWindow ShadowMapWindowFor(const BakePlan& plan, const TileRect& tile,
                                   const glm::dvec2& sample, double z_near);

}  // namespace pdsm

#endif  // PDSM_CORE_BAKE_TILE_REACH_H_
