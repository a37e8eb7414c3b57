// How a refinement level's tiles are grouped (docs/algorithms.md section 10). A level's rays are
// only the refined pixels' sub-pixels: around a contact ring they are a thin band, across a
// caster's self-shadows they fill whole regions. A group renders one shadow map per sample
// covering the box of its rays, so large groups waste texels on a ring, and small ones submit
// the casters above a region once per map instead of once: the level takes the group side, up
// to the base's rule (GroupSideInTiles), that minimizes an estimate of its maps' cost.
#ifndef PDSM_CORE_BAKE_LEVEL_GROUPS_H_
#define PDSM_CORE_BAKE_LEVEL_GROUPS_H_

#include "core/bake/bake_plan.h"

namespace pdsm {

// llvmpipe's cost of one shadow map, per caster triangle submitted and per texel of its
// window, measured with pdsm bake on the dragon (202,520 casters, 4x level) and a box on a
// plane (12 casters, 8x level) on the 2-core machine: about 85 ns a triangle, 30 ns a texel
// (docs/performance.md, "Adaptive resolution").
inline constexpr double kMapSecondsPerTriangle = 85e-9;
inline constexpr double kMapSecondsPerTexel = 30e-9;

// The side, in tiles, of the level's groups: of 1, 2, 4, ... up to level.group_side, the one
// whose maps' estimated cost is least (the larger on a tie). The estimate takes, per group with
// rays, the box of its rays seen from the light's centre, its texels on the level's lattice and
// the caster triangles whose clusters' boxes project into it. Deterministic: depends only on
// the plan. REQUIRES: a refinement level's plan (PlanRefinementLevel), group_side set by the
// base's rule.
int LevelGroupSide(const BakePlan& level);

}  // namespace pdsm

#endif  // PDSM_CORE_BAKE_LEVEL_GROUPS_H_
