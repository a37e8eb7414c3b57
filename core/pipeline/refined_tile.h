// The last step of a refined bake (issue #15 item 2; docs/algorithms.md section 10): a base
// tile whose refined pixels (core/bake/refined_pixels.h) take the sub-pixel functions their
// refinement level baked, as refined pixels of the file (core/pdsm/refined_pixel.h). The local
// bake and the coordinator both splice with this, so their files are the same bytes.
#ifndef PDSM_CORE_PIPELINE_REFINED_TILE_H_
#define PDSM_CORE_PIPELINE_REFINED_TILE_H_

#include <functional>
#include <optional>
#include <span>
#include <vector>

#include "absl/status/statusor.h"
#include "core/bake/bake_plan.h"
#include "core/bake/receiver_windows.h"
#include "core/bake/refined_pixels.h"
#include "core/pdsm/pdsm_image.h"

namespace pdsm {

// The level's finished tile `tile_index` (of its plan's grid), or nullopt when it stored none
// (no caster reaches its rays). Called from several threads at once.
using LevelTileSource = std::function<absl::StatusOr<std::optional<PdsmTile>>(int tile_index)>;

// The function of a ray nothing shadows in its windows: A = 0 in each, NaN around them (the
// layout of core/bake/surface_function.h); no vertex for no window. A sub-function without
// vertex would be undefined where the ray has windows.
std::vector<Vertex> LitInWindows(std::span<const DepthWindow> windows);

// `base` with each of `pixels` (its refined pixels, RefinedPixels::Tile) refined by the level
// `level` (PlanRefinementLevel): its function kept as its own, its sub-pixel (i, j) the function
// of the level's pixel (f x + i, f y + j), or LitInWindows of that ray's scan windows where the
// function has no vertex. Level tiles are read through `level_tile`, each at most once.
// Errors: `level_tile`'s.
absl::StatusOr<PdsmTile> SpliceRefinedTile(const PdsmTile& base,
                                           std::span<const RefinedPixel> pixels,
                                           const BakePlan& level,
                                           const LevelTileSource& level_tile);

}  // namespace pdsm

#endif  // PDSM_CORE_PIPELINE_REFINED_TILE_H_
