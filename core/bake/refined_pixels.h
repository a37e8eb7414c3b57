// The pixels of a refined bake that adaptive resolution refines (issue #15 item 2;
// docs/algorithms.md section 10): what SelectRefinement chose over the tiles of the base map,
// and what its refinement level bakes of them. A light has one level: every refined pixel takes
// the largest factor any of them asked for, because a level costs a set of shadow maps for all
// its pixels whatever their number (docs/performance.md, "Adaptive resolution"). The level is a
// plan of that factor times the base's resolution (PlanRefinementLevel) whose rays are the
// sub-pixels of the refined pixels, each scanned around the receivers within a sub-pixel of it
// inside its pixel's bands (its scan windows, core/bake/scan_windows.h).
//
// Immutable once made: safe to read from any thread.
#ifndef PDSM_CORE_BAKE_REFINED_PIXELS_H_
#define PDSM_CORE_BAKE_REFINED_PIXELS_H_

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "core/bake/bake_plan.h"
#include "core/bake/receiver_windows.h"

namespace pdsm {

// One refined pixel of the base map.
struct RefinedPixel {
  int x = 0, y = 0;                // base pixel
  std::vector<DepthWindow> bands;  // sorted, disjoint, non-empty
  bool operator==(const RefinedPixel&) const = default;
};

class RefinedPixels {
 public:
  // For a base map of `geometry` cut in tiles of `tile_size` (a plan's header): `by_tile[t]` the
  // refined pixels of tile t, row-major, every one refined by `factor` (2, 4 or 8; 1 when there
  // is none). REQUIRES: by_tile has one entry per tile of the grid.
  RefinedPixels(const PdsmGeometry& geometry, int tile_size, int factor,
                std::vector<std::vector<RefinedPixel>> by_tile);

  int factor() const { return factor_; }
  int tiles() const { return static_cast<int>(by_tile_.size()); }  // the base grid's
  // Tile `tile_index`'s refined pixels, row-major.
  std::span<const RefinedPixel> Tile(int tile_index) const { return by_tile_[tile_index]; }
  int64_t count() const { return count_; }
  bool empty() const { return count_ == 0; }
  // The heap and struct bytes this holds (a coordinator counts a level's plan against
  // --max-planned-mib: server/plan_budget.h): reserved sizes, as core/bake/plan_memory.h counts.
  int64_t HeldBytes() const;

  // The bands of the level's tile `level_rect` (pixels of the level's grid), as windows: level
  // pixel (X, Y) holds those of base pixel (X / factor, Y / factor) when that pixel is refined,
  // none otherwise.
  TileWindows LevelBands(const TileRect& level_rect) const;
  // Whether the level's tile `level_rect` holds a ray of a refined pixel.
  bool LevelHasRays(const TileRect& level_rect) const;
  // The bounding box, in the level's pixels, of those rays (index unset); nullopt for none.
  std::optional<TileRect> LevelRayBounds(const TileRect& level_rect) const;

 private:
  // Calls visit(pixel) for each refined pixel in the base rectangle [x0, x1) x [y0, y1).
  template <typename Visit>
  void ForEachIn(int x0, int y0, int x1, int y1, Visit&& visit) const;

  PdsmGeometry geometry_;
  int tile_size_ = 1;
  int tiles_x_ = 0;
  int factor_ = 1;
  std::vector<std::vector<RefinedPixel>> by_tile_;
  int64_t count_ = 0;
};

}  // namespace pdsm

#endif  // PDSM_CORE_BAKE_REFINED_PIXELS_H_
