// Tile groups (thesis 3.3, "slices"; issue #11): the unit of rendering and of distribution.
// A task is (group, batch of samples): for each sample the worker renders one shadow map for
// the whole group — the union of what its rays can reach — and scan-converts every ray of the
// group through it, so a sample's map is rendered once for all the tiles it serves instead of
// once per tile. Groups are squares of G x G tiles of the grid (edge groups are cut), G the
// largest power of two for which a group's shadow map stays within kShadowMapTexelBudget for
// the widest sample at the nearest depth rays are scanned from, and its pixels within
// kMaxGroupPixels (what one task result holds). Computed from the plan alone, so every process
// of a bake cuts the same groups.
#ifndef PDSM_CORE_BAKE_TILE_GROUPS_H_
#define PDSM_CORE_BAKE_TILE_GROUPS_H_

#include <cstdint>
#include <vector>

namespace pdsm {

struct BakePlan;

// A task's result holds per-pixel offsets and events of every pixel of its group's tiles that a
// caster may reach (the others get no task): 2^22 pixels (2048^2) keep that within tens of
// MiB even where casters reach every tile.
inline constexpr int64_t kMaxGroupPixels = int64_t{1} << 22;

// A group as BakePlan::group() makes it.
struct TileGroup {
  int index = 0;
  int x0 = 0, y0 = 0, width = 0, height = 0;  // PDSM pixels covered by its tiles
  std::vector<int> tiles;                     // tile indices, row-major
};

// The group side in tiles: plan.tile_group_size when set, else the largest the budgets allow
// (>= 1). PlanBake stores it in plan.group_side; every tile is then in exactly one group.
// REQUIRES: the plan's tile grid, samples, lattice and scan floor set.
int GroupSideInTiles(const BakePlan& plan);

}  // namespace pdsm

#endif  // PDSM_CORE_BAKE_TILE_GROUPS_H_
