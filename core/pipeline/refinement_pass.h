// Adaptive resolution's pass over a light's finished base map (issue #15 item 2;
// docs/algorithms.md section 10), the same in the local bake and the coordinator: choose the
// pixels to refine from the stored base tiles; then the refinement level, an ordinary bake of
// PlanRefinementLevel(…, refined); then splice its sub-pixel functions into the base tiles.
#ifndef PDSM_CORE_PIPELINE_REFINEMENT_PASS_H_
#define PDSM_CORE_PIPELINE_REFINEMENT_PASS_H_

#include <functional>
#include <memory>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/bake/bake_plan.h"
#include "core/bake/refined_pixels.h"
#include "core/pdsm/pdsm_image.h"
#include "core/pipeline/refined_tile.h"

namespace pdsm {

// Base tile `tile_index` as it was stored (decoded). Called from several threads at once.
using BaseTileSource = std::function<absl::StatusOr<PdsmTile>(int tile_index)>;

// The refined pixels of every tile of `base` (SelectRefinement with the receivers' windows:
// REQUIRES the plan's receivers, which PlanBake keeps for a refined plan), read from `tiles`,
// on up to `threads` threads, all refined by the largest factor any pixel asks for
// (core/bake/refined_pixels.h says why). The result depends only on the plan and the tiles.
// Errors: `tiles`'.
absl::StatusOr<std::shared_ptr<const RefinedPixels>> SelectRefinedPixels(
    const BakePlan& base, const BaseTileSource& tiles, int threads);

// For each base tile with refined pixels: SpliceRefinedTile of it with the tiles of `level`,
// the base's refinement level (its plan, holding the refined pixels), read through
// `level_tile`; handed to `store` (called from several threads at once), on up to `threads`
// threads. Errors: the sources' and `store`'s (the first; the tiles left are then not done).
absl::Status SpliceRefinedTiles(const BakePlan& base, const BakePlan& level,
                                const BaseTileSource& tiles, const LevelTileSource& level_tile,
                                const std::function<absl::Status(const PdsmTile&)>& store,
                                int threads);

}  // namespace pdsm

#endif  // PDSM_CORE_PIPELINE_REFINEMENT_PASS_H_
