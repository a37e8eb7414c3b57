// What a task's tile group needs before its first shadow map, computed once per (group, tiles)
// and reused by every batch of samples of it: per tile, its reach (core/bake/tile_reach.h),
// its scan windows (surfaces-only bakes, refinement levels: core/bake/scan_windows.h) and the
// blocks of rays to scan with their depth ranges; for the group, the union of its tiles' casters in
// the plan's cluster order, which is what the renderer holds, and each cluster's run of it with the
// run's bounding box, so that every sample's shadow map draws only the clusters its window can see.
#ifndef PDSM_WORKER_PREPARED_GROUP_H_
#define PDSM_WORKER_PREPARED_GROUP_H_

#include <cstdint>
#include <optional>
#include <vector>

#include <glm/glm.hpp>

#include "core/bake/bake_plan.h"
#include "core/bake/receiver_windows.h"
#include "core/bake/shadow_map_lattice.h"
#include "worker/shadow_map_renderer.h"

namespace pdsm {

// Rays of one block scanned from z_begin to z_end (+infinity: to w = 0).
struct BlockScan {
  TileRect rect;
  double z_begin, z_end;
};

struct PreparedTile {
  TileRect rect;
  bool has_casters = false;            // false: all lit, nothing to render or scan
  std::optional<TileWindows> windows;  // ScanWindows: surfaces-only bakes, refinement levels
  std::vector<BlockScan> blocks;       // empty: all lit
};

// One cluster's run of the uploaded triangles and its bounding box, light space.
struct UploadedCluster {
  DrawRange range;
  glm::dvec3 lo, hi;
};

struct PreparedGroup {
  int group_index = -1;
  std::vector<int> tiles;              // the task's tiles of the group
  std::vector<PreparedTile> prepared;  // one per tile, same order
  std::vector<uint32_t> triangles;     // plan.casters triangles to upload, in this order
  std::vector<UploadedCluster> clusters;
  bool empty() const { return triangles.empty(); }
};

// REQUIRES: `tiles` are tiles of plan.group(group_index).
PreparedGroup PrepareGroup(const BakePlan& plan, int group_index, const std::vector<int>& tiles);

// The lattice window holding every block's clipped ray segments for this sample: the one
// shadow map the group's tiles need. Empty (width 0) when no block is scanned.
ShadowMapWindow GroupWindow(const BakePlan& plan, const PreparedGroup& group,
                            const glm::dvec2& sample);

// The runs of the clusters whose projection for this sample can touch `window` (conservative:
// a cluster left out cannot cover any of its texels), in upload order.
std::vector<DrawRange> VisibleClusters(const BakePlan& plan, const PreparedGroup& group,
                                       const glm::dvec2& sample, const ShadowMapWindow& window);

}  // namespace pdsm

#endif  // PDSM_WORKER_PREPARED_GROUP_H_
