// The depth windows a tile's rays are scanned over, and its functions are defined on, when a
// bake scans only part of each ray: a surfaces-only plan's receiver windows
// (core/bake/receiver_windows.h, docs/algorithms.md section 7b) and a refinement level's
// receiver windows (at its own pitch) inside the bands of its refined pixels
// (core/bake/refined_pixels.h, section 10). The worker's scan
// (worker/prepared_group.h) and the tile assembly (core/pipeline/tile_assembly.h) both ask
// here, so they always agree.
#ifndef PDSM_CORE_BAKE_SCAN_WINDOWS_H_
#define PDSM_CORE_BAKE_SCAN_WINDOWS_H_

#include <optional>

#include "core/bake/bake_plan.h"
#include "core/bake/receiver_windows.h"

namespace pdsm {

// nullopt for a plan whose rays are scanned whole. Deterministic: depends only on the plan and
// the tile.
std::optional<TileWindows> ScanWindows(const BakePlan& plan, const TileRect& tile);

}  // namespace pdsm

#endif  // PDSM_CORE_BAKE_SCAN_WINDOWS_H_
