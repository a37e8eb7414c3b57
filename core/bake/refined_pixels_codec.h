// The refined pixels of a light (core/bake/refined_pixels.h) as bytes: how the coordinator
// hands the pixels it chose from the base map to the workers that bake the refinement level
// (FetchRefinement, proto/pdsm/v1/workers.proto), so that every worker plans the level the
// coordinator planned (PlanRefinementLevel; the level's plan fingerprint covers the pixels).
//
// Layout, little-endian (core/util/little_endian.h): "PDSMREFP", uint32 version (1), int32
// factor, uint32 tile count; then for each tile of the base grid in order: uint32 pixel count,
// and for each pixel (row-major within the tile): int32 x, int32 y (base pixels), uint32 band
// count, then float64 lo, hi per band (light-space depth, sorted and disjoint). Exact: the
// doubles round-trip bit for bit.
#ifndef PDSM_CORE_BAKE_REFINED_PIXELS_CODEC_H_
#define PDSM_CORE_BAKE_REFINED_PIXELS_CODEC_H_

#include <memory>
#include <string>

#include "absl/status/statusor.h"
#include "core/bake/bake_plan.h"
#include "core/bake/refined_pixels.h"

namespace pdsm {

std::string EncodeRefinedPixels(const RefinedPixels& refined);

// The refined pixels `bytes` hold, for the base map of `base` (its geometry and tile grid).
// DATA_LOSS naming `label` for bytes that are not such a blob of this grid: a bad magic,
// version or factor, a tile count other than the grid's, a pixel outside its tile or out of
// order, a band that is empty, not finite, or out of order, bytes missing or left over.
absl::StatusOr<std::shared_ptr<const RefinedPixels>> DecodeRefinedPixels(const std::string& bytes,
                                                                         const BakePlan& base,
                                                                         const std::string& label);

}  // namespace pdsm

#endif  // PDSM_CORE_BAKE_REFINED_PIXELS_CODEC_H_
