#include "core/bake/scan_windows.h"

#include <algorithm>

#include "core/bake/refined_pixels.h"

namespace pdsm {
namespace {

// Per pixel, the intersections of `a`'s windows with `b`'s (both of the same rectangle).
TileWindows Intersect(const TileWindows& a, const TileWindows& b) {
  TileWindows out;
  out.rect = a.rect;
  out.offsets.assign(a.offsets.size(), 0);
  for (size_t p = 0; p + 1 < a.offsets.size(); ++p) {
    for (const DepthWindow& u : a.Pixel(p)) {
      for (const DepthWindow& v : b.Pixel(p)) {
        const double lo = std::max(u.lo, v.lo), hi = std::min(u.hi, v.hi);
        if (lo < hi) out.windows.push_back(DepthWindow{lo, hi});
      }
    }
    out.offsets[p + 1] = out.windows.size();
  }
  return out;
}

}  // namespace

std::optional<TileWindows> ScanWindows(const BakePlan& plan, const TileRect& tile) {
  if (plan.refined != nullptr) {
    // A refinement level: each sub-pixel ray around the receivers a query there blends it for
    // (within one of the level's pixels), inside its pixel's bands.
    TileWindows bands = plan.refined->LevelBands(tile);
    if (bands.windows.empty()) return bands;
    return Intersect(bands, ComputeReceiverWindows(plan, tile));
  }
  if (plan.header.surfaces_only) return ComputeReceiverWindows(plan, tile);
  return std::nullopt;
}

}  // namespace pdsm
