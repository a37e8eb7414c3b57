// A light's casters, gathered from the scene index (issue #12, large worlds): a street lamp in
// a world of 10^6 triangles carries the few near it, not the world, through its planning, its
// tile marking, its tasks and each worker's memory, and plans in time for what it keeps plus a
// box test per cluster of the world.
//
// The tiles are marked (BakePlan::tile_has_casters) with every caster cluster of the index,
// kept or not, so that what is left out never moves a mark: a tile's task, even one whose reach
// only holds triangles that cannot shadow, widens its group's shadow-map windows, and a
// different window rounds some triangle edges to the other side of a texel centre. A triangle
// is left out only where every tile's reach drops it (CasterReachBound, core/bake/tile_reach.h),
// so every tile keeps the same triangles in the same order, with the same ray blocks and depths,
// and every shadow map draws the same triangles: leaving out changes no byte
// (PlanCasters::kEvery keeps every caster, to compare against). The reach is conservative (it
// keeps triangles that cross the near clip plane or the light's plane where only their undrawn
// part is in reach), so a tighter cut, to the region between a light sample and any ray, or a
// tile marking over the kept casters alone, dropped blocks that shadow nothing yet widened
// windows, and moved answers by one sample at a few points (a street lamp of
// bench/large_world.py, 2026-12-03).
#ifndef PDSM_CORE_BAKE_CASTER_CULLING_H_
#define PDSM_CORE_BAKE_CASTER_CULLING_H_

#include "core/bake/bake_plan.h"
#include "core/bake/scene_index.h"

namespace pdsm {

// Fills plan->casters (light space, float, in the index's order, only the vertices they use,
// with UVs and masks where the scene has alpha-tested casters), caster_clusters (each index
// cluster's kept triangles with their light-space bounds; empty ones go), masks,
// tile_has_casters and casters_left_out.
// REQUIRES: the plan's geometry, tiles, samples, lattice and clip depths set; `index` built
// from the scene the plan is made of.
void GatherCasters(const SceneIndex& index, PlanCasters which, BakePlan* plan);

}  // namespace pdsm

#endif  // PDSM_CORE_BAKE_CASTER_CULLING_H_
