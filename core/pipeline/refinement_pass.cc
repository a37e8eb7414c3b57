#include "core/pipeline/refinement_pass.h"

#include <algorithm>
#include <atomic>
#include <optional>
#include <utility>
#include <vector>

#include "absl/synchronization/mutex.h"
#include "core/bake/receiver_windows.h"
#include "core/bake/refinement_selection.h"
#include "core/util/work_queue.h"

namespace pdsm {
namespace {

// Runs work(t) for t in [0, count) on up to `threads` threads; the first error stops the rest.
absl::Status ForEachTile(int count, int threads,
                         const std::function<absl::Status(int tile)>& work) {
  std::atomic<int> next{0};
  absl::Mutex mu;
  absl::Status first;
  RunOnAllCores(static_cast<size_t>(std::max(1, threads)), [&] {
    for (int t = next++; t < count; t = next++) {
      absl::Status s = work(t);
      if (s.ok()) continue;
      absl::MutexLock lock(&mu);
      if (first.ok()) first = std::move(s);
      next = count;
    }
  });
  return first;
}

// Tile `tile`'s refined pixels: its function and its four neighbours' (the pairs across its
// edges), read from `tiles`.
absl::StatusOr<std::vector<PixelRefinement>> SelectTile(const BakePlan& base, int tile,
                                                        const BaseTileSource& tiles) {
  const TileRect rect = base.tile(tile);
  // The tile and its 4-neighbours, by grid offset; a pair with a pixel in the tile reads no
  // other tile.
  std::vector<std::pair<TileRect, PdsmTile>> near;
  bool any_vertex = false;
  for (const auto& [dx, dy] :
       {std::pair{0, 0}, std::pair{-1, 0}, std::pair{1, 0}, std::pair{0, -1}, std::pair{0, 1}}) {
    const int tx = tile % base.tiles_x + dx, ty = tile / base.tiles_x + dy;
    if (tx < 0 || ty < 0 || tx >= base.tiles_x || ty >= base.tiles_y) continue;
    const int index = ty * base.tiles_x + tx;
    absl::StatusOr<PdsmTile> t = tiles(index);
    if (!t.ok()) return t.status();
    any_vertex = any_vertex || !t->vertices.empty();
    near.emplace_back(base.tile(index), *std::move(t));
  }
  if (!any_vertex)
    return std::vector<PixelRefinement>(static_cast<size_t>(rect.width) * rect.height);
  const auto function_at = [&](int x, int y) -> std::span<const Vertex> {
    for (const auto& [r, t] : near) {
      if (x >= r.x0 && x < r.x0 + r.width && y >= r.y0 && y < r.y0 + r.height) {
        return t.Function(x - r.x0, y - r.y0);
      }
    }
    return {};  // a corner of the grown rectangle: in no pair with a pixel of the tile
  };
  const PdsmGeometry& g = base.geometry();
  return SelectRefinement(g, rect, base.header.max_refinement, ComputePairReceivers(base, rect),
                          function_at);
}

}  // namespace

absl::StatusOr<std::shared_ptr<const RefinedPixels>> SelectRefinedPixels(
    const BakePlan& base, const BaseTileSource& tiles, int threads) {
  std::vector<std::vector<RefinedPixel>> by_tile(base.tile_count());
  std::vector<int> factor_of_tile(base.tile_count(), 1);  // the largest a tile's pixels ask for
  const absl::Status s = ForEachTile(base.tile_count(), threads, [&](int t) -> absl::Status {
    absl::StatusOr<std::vector<PixelRefinement>> pixels = SelectTile(base, t, tiles);
    if (!pixels.ok()) return pixels.status();
    const TileRect rect = base.tile(t);
    for (int j = 0; j < rect.height; ++j) {
      for (int i = 0; i < rect.width; ++i) {
        PixelRefinement& r = (*pixels)[static_cast<size_t>(j) * rect.width + i];
        if (r.factor == 1) continue;
        factor_of_tile[t] = std::max(factor_of_tile[t], r.factor);
        by_tile[t].push_back(RefinedPixel{rect.x0 + i, rect.y0 + j, std::move(r.bands)});
      }
    }
    return absl::OkStatus();
  });
  if (!s.ok()) return s;
  // One level for the light: every refined pixel takes the largest factor asked for.
  const int factor = *std::max_element(factor_of_tile.begin(), factor_of_tile.end());
  return std::make_shared<const RefinedPixels>(base.geometry(), base.header.tile_size, factor,
                                               std::move(by_tile));
}

absl::Status SpliceRefinedTiles(const BakePlan& base, const BakePlan& level,
                                const BaseTileSource& tiles, const LevelTileSource& level_tile,
                                const std::function<absl::Status(const PdsmTile&)>& store,
                                int threads) {
  const RefinedPixels& refined = *level.refined;
  std::vector<int> refined_tiles;
  for (int t = 0; t < base.tile_count(); ++t) {
    if (!refined.Tile(t).empty()) refined_tiles.push_back(t);
  }
  return ForEachTile(static_cast<int>(refined_tiles.size()), threads, [&](int k) -> absl::Status {
    const int t = refined_tiles[k];
    absl::StatusOr<PdsmTile> tile = tiles(t);
    if (!tile.ok()) return tile.status();
    absl::StatusOr<PdsmTile> spliced = SpliceRefinedTile(*tile, refined.Tile(t), level, level_tile);
    if (!spliced.ok()) return spliced.status();
    return store(*spliced);
  });
}

}  // namespace pdsm
