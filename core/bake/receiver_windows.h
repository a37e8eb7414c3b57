// Surfaces-only bakes (docs/algorithms.md, "Surfaces only"): for each PDSM ray, the depth
// windows around the receiver surfaces a query may need. A query at a point on a receiver
// blends the four pixels around its projection, so the windows of a pixel hold the depths of
// every receiver point that projects within one pixel pitch of the pixel's centre (its
// bilinear support), found from the receivers' triangles without any rendering.
#ifndef PDSM_CORE_BAKE_RECEIVER_WINDOWS_H_
#define PDSM_CORE_BAKE_RECEIVER_WINDOWS_H_

#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "core/bake/bake_plan.h"

namespace pdsm {

// A closed depth interval [lo, hi], light-space z.
struct DepthWindow {
  double lo = 0, hi = 0;
  bool operator==(const DepthWindow&) const = default;
};

// Per-pixel windows of one tile, row-major from (rect.x0, rect.y0): sorted, disjoint,
// each padded for float rounding (kWindowRelativePad).
struct TileWindows {
  TileRect rect;
  std::vector<uint64_t> offsets;  // rect.width * rect.height + 1
  std::vector<DepthWindow> windows;

  std::span<const DepthWindow> Pixel(size_t p) const {
    return {windows.data() + offsets[p], windows.data() + offsets[p + 1]};
  }
};

// Relative padding of every window, in units of its depth: 2^-15, 16 times the events'
// consolidation distance, so neither float rounding of depths nor consolidation moves an
// event of a receiver point out of its window.
inline constexpr double kWindowRelativePad = 0x1.0p-15;

// Deterministic: depends only on the plan and the tile.
TileWindows ComputeReceiverWindows(const BakePlan& plan, const TileRect& tile);

// The same for the rays through another grid of points: point (i, j) of `grid` (x0 <= i <
// x0 + width, ...) is the ray through pixel coordinates (i + offset.x, j + offset.y), and its
// windows hold the receiver depths over the square of half-side `half_pixels` pixel pitches
// around it. ComputeReceiverWindows is the grid of pixel centres (offset 0.5) with half-side 1;
// a small half-side gives the receiver depths along the ray itself (adaptive resolution compares
// neighbouring rays there, at the points between them: core/bake/refinement_selection.h).
TileWindows ComputeReceiverWindowsAt(const BakePlan& plan, const TileRect& grid,
                                     const glm::dvec2& offset, double half_pixels);
// The same over `receivers` (of the plan's light space) instead of plan.receivers: a refined
// plan's RefinableReceivers().
TileWindows ComputeReceiverWindowsAt(const BakePlan& plan, const LightSpaceMesh& receivers,
                                     const TileRect& grid, const glm::dvec2& offset,
                                     double half_pixels);

}  // namespace pdsm

#endif  // PDSM_CORE_BAKE_RECEIVER_WINDOWS_H_
