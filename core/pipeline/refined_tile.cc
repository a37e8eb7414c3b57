#include "core/pipeline/refined_tile.h"

#include <cmath>
#include <limits>
#include <map>
#include <utility>

#include "core/bake/scan_windows.h"
#include "core/pdsm/refined_pixel.h"

namespace pdsm {
namespace {

// A level tile as the splice reads it: its functions (none stored: all empty) and the windows
// its rays were scanned over.
struct LevelTile {
  std::optional<PdsmTile> tile;
  TileWindows windows;
};

// The bands as the file stores them: in float, rounded outwards.
std::vector<RefinedBand> StoredBands(std::span<const DepthWindow> bands) {
  std::vector<RefinedBand> out;
  out.reserve(bands.size());
  for (const DepthWindow& b : bands) {
    float lo = static_cast<float>(b.lo), hi = static_cast<float>(b.hi);
    if (lo > b.lo) lo = std::nextafter(lo, -std::numeric_limits<float>::infinity());
    if (hi < b.hi) hi = std::nextafter(hi, std::numeric_limits<float>::infinity());
    out.push_back(RefinedBand{lo, hi});
  }
  return out;
}

}  // namespace

std::vector<Vertex> LitInWindows(std::span<const DepthWindow> windows) {
  constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
  std::vector<Vertex> out;
  if (windows.empty()) return out;
  out.push_back(Vertex{kUndefinedFrom, kNaN});
  for (const DepthWindow& w : windows) {
    out.push_back(Vertex{static_cast<float>(w.lo), 0.0f});
    out.push_back(Vertex{static_cast<float>(w.hi), 0.0f});
    out.push_back(Vertex{static_cast<float>(w.hi), kNaN});
  }
  return out;
}

absl::StatusOr<PdsmTile> SpliceRefinedTile(const PdsmTile& base,
                                           std::span<const RefinedPixel> pixels,
                                           const BakePlan& level,
                                           const LevelTileSource& level_tile) {
  const int f = level.refinement;
  const int tile_size = level.header.tile_size;
  std::map<int, LevelTile> levels;  // the level tiles read, by index
  // Sub-pixel ray (x, y) of the level's grid, as the file stores it.
  const auto sub_function = [&](int x, int y) -> absl::StatusOr<std::vector<Vertex>> {
    const int index = level.TileIndexAt(x / tile_size * tile_size, y / tile_size * tile_size);
    auto it = levels.find(index);
    if (it == levels.end()) {
      absl::StatusOr<std::optional<PdsmTile>> tile = level_tile(index);
      if (!tile.ok()) return tile.status();
      const TileRect rect = level.tile(index);
      it = levels
               .emplace(index, LevelTile{*std::move(tile),
                                         ScanWindows(level, rect).value_or(TileWindows{})})
               .first;
    }
    const LevelTile& t = it->second;
    const TileRect& rect = t.windows.rect;
    const int i = x - rect.x0, j = y - rect.y0;
    const std::span<const Vertex> stored =
        t.tile ? t.tile->Function(i, j) : std::span<const Vertex>();
    if (!stored.empty()) return std::vector<Vertex>(stored.begin(), stored.end());
    return LitInWindows(t.windows.Pixel(static_cast<size_t>(j) * rect.width + i));
  };

  PdsmTile out;
  out.x0 = base.x0, out.y0 = base.y0, out.width = base.width, out.height = base.height;
  out.samples = base.samples;
  out.offsets.reserve(base.offsets.size());
  out.offsets.push_back(0);
  size_t next = 0;  // the next of `pixels`, row-major like the tile's pixels
  std::vector<std::vector<Vertex>> subs(static_cast<size_t>(f) * f);
  for (int j = 0; j < base.height; ++j) {
    for (int i = 0; i < base.width; ++i) {
      const std::span<const Vertex> own = base.Function(i, j);
      if (next < pixels.size() && pixels[next].x == base.x0 + i && pixels[next].y == base.y0 + j) {
        const RefinedPixel& p = pixels[next++];
        for (int b = 0; b < f; ++b) {
          for (int a = 0; a < f; ++a) {
            absl::StatusOr<std::vector<Vertex>> sub = sub_function(f * p.x + a, f * p.y + b);
            if (!sub.ok()) return sub.status();
            subs[static_cast<size_t>(a) + static_cast<size_t>(f) * b] = *std::move(sub);
          }
        }
        AppendRefinedPixel(f, StoredBands(p.bands), own, subs, &out.vertices);
      } else {
        out.vertices.insert(out.vertices.end(), own.begin(), own.end());
      }
      out.offsets.push_back(out.vertices.size());
    }
  }
  return out;
}

}  // namespace pdsm
