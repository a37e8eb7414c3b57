// Tiles no caster reaches (BakePlan::tile_has_casters false): their rays meet no shadow, so
// they need no task, and what they hold follows from the plan alone. The local bake writes
// them like any tile; the coordinator stores only that they are done and makes them again
// when it writes the file or serves one (server/stored_job.h), so a sparse world of 2^18
// tiles costs no file per empty tile.
#ifndef PDSM_CORE_PIPELINE_UNREACHED_TILE_H_
#define PDSM_CORE_PIPELINE_UNREACHED_TILE_H_

#include <cstdint>

#include "core/bake/bake_plan.h"
#include "core/events/event.h"
#include "core/pdsm/pdsm_image.h"

namespace pdsm {

// True when the plan knows that no caster reaches tile `tile_index` (a plan without the
// per-tile flags reaches every tile). REQUIRES: tile_index in [0, plan.tile_count()).
bool IsUnreachedTile(const BakePlan& plan, int tile_index);

// The result a task returns for tile `rect` when no sample shadows any of its rays: every
// pixel's list empty.
TileEvents NoShadowEvents(const TileRect& rect);

struct UnreachedTile {
  PdsmTile tile;            // all lit: no vertex
  int tile_samples = 0;     // adaptive bakes: the pilot's samples, at which it converged; else 0
  int samples_skipped = 0;  // adaptive bakes: the samples it never needed
};

// What a task for the tile would have led to, judged as every stage rule judges a tile with
// no event (fixed-count tiles complete, adaptive ones converge at their pilot), assembled:
// the same bytes the engine stores. Pure; thread-safe.
UnreachedTile MakeUnreachedTile(const BakePlan& plan, int tile_index);

// What every such tile of `plan` holds besides its rectangle: MakeUnreachedTile's
// tile.samples, the same for all of them (the pilot's samples in an adaptive bake, else 0),
// found by making one. For writers of many such tiles (a sparse world has 2^18), which then
// need no assembly each: the tile has no vertex (tile_chunk.h's EmptyTileChunks).
int UnreachedTileSamples(const BakePlan& plan);

}  // namespace pdsm

#endif  // PDSM_CORE_PIPELINE_UNREACHED_TILE_H_
