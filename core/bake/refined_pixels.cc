#include "core/bake/refined_pixels.h"

#include <algorithm>
#include <utility>

namespace pdsm {

RefinedPixels::RefinedPixels(const PdsmGeometry& geometry, int tile_size, int factor,
                             std::vector<std::vector<RefinedPixel>> by_tile)
    : geometry_(geometry),
      tile_size_(std::max(1, tile_size)),
      tiles_x_((geometry.width + tile_size_ - 1) / tile_size_),
      factor_(factor),
      by_tile_(std::move(by_tile)) {
  for (const std::vector<RefinedPixel>& tile : by_tile_)
    count_ += static_cast<int64_t>(tile.size());
}

int64_t RefinedPixels::HeldBytes() const {
  // Each pixel's bands are a small heap block of their own, where the allocator's header and
  // rounding (16 bytes with glibc) are a third of what it holds: counted, unlike a plan's few
  // large vectors (core/bake/plan_memory.h).
  constexpr int64_t kBlockOverhead = 16;
  int64_t bytes = sizeof(RefinedPixels) +
                  static_cast<int64_t>(by_tile_.capacity() * sizeof(std::vector<RefinedPixel>));
  for (const std::vector<RefinedPixel>& tile : by_tile_) {
    bytes += static_cast<int64_t>(tile.capacity() * sizeof(RefinedPixel));
    for (const RefinedPixel& pixel : tile) {
      if (pixel.bands.capacity() == 0) continue;
      bytes += static_cast<int64_t>(pixel.bands.capacity() * sizeof(DepthWindow)) + kBlockOverhead;
    }
  }
  return bytes;
}

template <typename Visit>
void RefinedPixels::ForEachIn(int x0, int y0, int x1, int y1, Visit&& visit) const {
  x0 = std::max(x0, 0), y0 = std::max(y0, 0);
  x1 = std::min(x1, geometry_.width), y1 = std::min(y1, geometry_.height);
  if (x0 >= x1 || y0 >= y1) return;
  for (int ty = y0 / tile_size_; ty <= (y1 - 1) / tile_size_; ++ty) {
    for (int tx = x0 / tile_size_; tx <= (x1 - 1) / tile_size_; ++tx) {
      for (const RefinedPixel& p : by_tile_[static_cast<size_t>(ty) * tiles_x_ + tx]) {
        if (p.x >= x0 && p.x < x1 && p.y >= y0 && p.y < y1) visit(p);
      }
    }
  }
}

TileWindows RefinedPixels::LevelBands(const TileRect& level_rect) const {
  const int f = factor_;
  TileWindows out;
  out.rect = level_rect;
  const size_t pixels = static_cast<size_t>(level_rect.width) * level_rect.height;
  std::vector<const RefinedPixel*> of_pixel(pixels, nullptr);
  // The base pixels the level tile's rays subdivide.
  ForEachIn(level_rect.x0 / f, level_rect.y0 / f, (level_rect.x0 + level_rect.width + f - 1) / f,
            (level_rect.y0 + level_rect.height + f - 1) / f, [&](const RefinedPixel& p) {
              for (int y = std::max(p.y * f, level_rect.y0);
                   y < std::min((p.y + 1) * f, level_rect.y0 + level_rect.height); ++y) {
                for (int x = std::max(p.x * f, level_rect.x0);
                     x < std::min((p.x + 1) * f, level_rect.x0 + level_rect.width); ++x) {
                  of_pixel[static_cast<size_t>(y - level_rect.y0) * level_rect.width +
                           (x - level_rect.x0)] = &p;
                }
              }
            });
  out.offsets.assign(pixels + 1, 0);
  for (size_t k = 0; k < pixels; ++k) {
    if (of_pixel[k] != nullptr) {
      out.windows.insert(out.windows.end(), of_pixel[k]->bands.begin(), of_pixel[k]->bands.end());
    }
    out.offsets[k + 1] = out.windows.size();
  }
  return out;
}

bool RefinedPixels::LevelHasRays(const TileRect& level_rect) const {
  return LevelRayBounds(level_rect).has_value();
}

std::optional<TileRect> RefinedPixels::LevelRayBounds(const TileRect& level_rect) const {
  const int f = factor_;
  int x0 = level_rect.x0 + level_rect.width, y0 = level_rect.y0 + level_rect.height;
  int x1 = level_rect.x0, y1 = level_rect.y0;
  ForEachIn(level_rect.x0 / f, level_rect.y0 / f, (level_rect.x0 + level_rect.width + f - 1) / f,
            (level_rect.y0 + level_rect.height + f - 1) / f, [&](const RefinedPixel& p) {
              x0 = std::min(x0, std::max(p.x * f, level_rect.x0));
              y0 = std::min(y0, std::max(p.y * f, level_rect.y0));
              x1 = std::max(x1, std::min((p.x + 1) * f, level_rect.x0 + level_rect.width));
              y1 = std::max(y1, std::min((p.y + 1) * f, level_rect.y0 + level_rect.height));
            });
  if (x0 >= x1 || y0 >= y1) return std::nullopt;
  return TileRect{0, x0, y0, x1 - x0, y1 - y0};
}

}  // namespace pdsm
