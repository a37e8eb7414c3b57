// The coordinator's last steps for one tile (thesis 3.1-3.2): merge the event lists of all its
// sample batches, consolidate, turn counts into attenuation and compress. The merge is exact
// integer arithmetic, so the tile is the same whatever the batches and their order.
#ifndef PDSM_CORE_PIPELINE_TILE_ASSEMBLY_H_
#define PDSM_CORE_PIPELINE_TILE_ASSEMBLY_H_

#include <cstdint>
#include <span>

#include "absl/status/statusor.h"
#include "core/bake/bake_plan.h"
#include "core/bake/receiver_windows.h"
#include "core/events/event.h"
#include "core/pdsm/pdsm_image.h"
#include "core/pipeline/event_spill.h"

namespace pdsm {

struct AssemblyStats {
  int64_t merged_events = 0;        // after merging batches
  int64_t consolidated_events = 0;  // after consolidation
  int64_t vertices = 0;             // after compression
  double seconds = 0;
  void Add(const AssemblyStats& o);
};

// REQUIRES: `parts` are results for the same tile whose batches together cover every sample
// of the bake exactly once; a counted bake (KeyingOf(header) == kCounts: a sample-keyed one
// needs the plan's samples, AssemblePlanTile). `windows`: the tile's receiver windows
// (ComputeReceiverWindows) when header.surfaces_only, else null.
PdsmTile AssembleTile(const PdsmHeader& header, std::span<const TileEvents> parts,
                      AssemblyStats* stats, const TileWindows* windows = nullptr);

// Adaptive bakes (core/bake/adaptive_sampling.h): `parts` cover the first `tile_samples`
// samples exactly once, and attenuation is count / tile_samples. Sets PdsmTile::samples.
PdsmTile AssembleTile(const PdsmHeader& header, std::span<const TileEvents> parts, int tile_samples,
                      AssemblyStats* stats, const TileWindows* windows = nullptr);

// The tile of `plan` the local bake and the coordinator both assemble: with its receiver
// windows when the bake is surfaces-only, as an adaptive tile when `tile_samples` > 0. The
// parts' runs are read back from `spill` a piece at a time and released.
// REQUIRES: `parts` cover the tile's samples exactly once; `spill` non-null when they have
// runs. Errors: the spill's, reading the runs back.
absl::StatusOr<PdsmTile> AssemblePlanTile(const BakePlan& plan, const TileParts& parts,
                                          EventSpill* spill, int tile_samples,
                                          AssemblyStats* stats);

}  // namespace pdsm

#endif  // PDSM_CORE_PIPELINE_TILE_ASSEMBLY_H_
