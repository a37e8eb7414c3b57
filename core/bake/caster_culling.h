// A light's plan keeps only the casters some tile of its PDSM can reach (issue #12, large
// worlds): a street lamp in a world of 10^6 triangles carries the few near it, not the world,
// through its tile marking, its tasks and each worker's memory.
//
// Byte-neutral by construction: a triangle is left out only where every tile's reach drops it
// (CastersSomeTileMayReach, core/bake/tile_reach.h), so every tile keeps the same triangles in
// the same order, with the same ray blocks and depths, and every shadow map draws the same
// triangles; the tiles are marked (BakePlan::tile_has_casters) before the cut, with every
// caster. Both matter because a shadow map's projection is fitted to its window, the union of
// its group's ray blocks: a different window rounds some triangle edges to the other side of a
// texel centre. The reach is conservative (it keeps triangles that cross the near clip plane or
// the light's plane where only their undrawn part is in reach), so a tighter cut, to the region
// between a light sample and any ray, or a tile marking over the cut clusters, dropped blocks
// that shadow nothing yet widened windows, and moved answers by one sample at a few points
// (a street lamp of bench/large_world.py, 2026-12-03).
#ifndef PDSM_CORE_BAKE_CASTER_CULLING_H_
#define PDSM_CORE_BAKE_CASTER_CULLING_H_

#include <cstddef>

namespace pdsm {

struct BakePlan;

// Leaves out of plan->casters the triangles no tile can reach, keeping the others in their
// order with their UVs and masks, and only the vertices they use; each cluster keeps its kept
// triangles with their bounds, and empty clusters go. Returns how many triangles were left out
// (0: the plan is untouched).
// REQUIRES: the plan's tiles, samples, lattice, clip depths and caster clusters set (PlanBake
// calls it last, after the tiles are marked).
size_t LeaveOutUnreachableCasters(BakePlan* plan);

}  // namespace pdsm

#endif  // PDSM_CORE_BAKE_CASTER_CULLING_H_
