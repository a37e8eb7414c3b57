// What a bake plan holds in memory, so that a coordinator can bound the plans it keeps in
// memory (server/plan_budget.h): exactly, from a plan, and as a lower bound before planning.
// Bytes are the plan's own struct and the sizes its vectors reserved (capacity times element
// size); the allocator's few bytes per block are not counted (a plan is a few large vectors
// plus one small one per tile group).
#ifndef PDSM_CORE_BAKE_PLAN_MEMORY_H_
#define PDSM_CORE_BAKE_PLAN_MEMORY_H_

#include <cstdint>

#include "core/bake/bake_plan.h"
#include "core/scene/scene.h"

namespace pdsm {

// The heap and struct bytes `plan` holds, as it stands (before or after
// ReleaseRenderGeometry).
int64_t PlanHeldBytes(const BakePlan& plan);

// A lower bound of PlanHeldBytes of the plan of a light baked with `bake`, once its render
// geometry is released, knowing only the settings and the sizes of the scene's receiving
// meshes (kept by a surfaces-only plan): what it holds at the least (all its tiles in one
// group), for admission checks made before anything is planned. Exact but for the grouping
// and the strings.
int64_t MinReleasedPlanBytes(const BakeSettings& bake, int64_t receiver_vertices,
                             int64_t receiver_triangles);

}  // namespace pdsm

#endif  // PDSM_CORE_BAKE_PLAN_MEMORY_H_
