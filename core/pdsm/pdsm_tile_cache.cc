#include "core/pdsm/pdsm_tile_cache.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "core/pdsm/pdsm_query.h"

namespace pdsm {
namespace {

// What a kept tile costs: its vectors' bytes, and nothing of its offsets when it holds no
// vertex (kept as an empty tile: every function empty).
int64_t TileBytes(const PdsmTile& tile) {
  return static_cast<int64_t>(sizeof(PdsmTile) + tile.offsets.capacity() * sizeof(uint64_t) +
                              tile.vertices.capacity() * sizeof(Vertex));
}

}  // namespace

PdsmTileCache::PdsmTileCache(PdsmReader reader, int64_t budget_bytes)
    : reader_(std::move(reader)), budget_bytes_(budget_bytes) {}

uint64_t PdsmTileCache::Key(int part, int tile_x, int tile_y) {
  // 16 bits of part (a file holds at most 65,536), 24 of each tile coordinate (maps up to
  // 2^24 tiles a side).
  return (uint64_t{static_cast<uint16_t>(part)} << 48) |
         (uint64_t{static_cast<uint32_t>(tile_y) & 0xffffff} << 24) |
         (static_cast<uint32_t>(tile_x) & 0xffffff);
}

absl::StatusOr<std::shared_ptr<const PdsmTile>> PdsmTileCache::Tile(int part, int tile_x,
                                                                    int tile_y) {
  const uint64_t key = Key(part, tile_x, tile_y);
  {
    absl::MutexLock lock(&mu_);
    if (auto it = entries_.find(key); it != entries_.end()) {
      lru_.splice(lru_.begin(), lru_, it->second.lru);
      return it->second.tile;
    }
  }
  absl::StatusOr<PdsmTile> read = reader_.ReadTile(part, tile_x, tile_y);
  if (!read.ok()) return read.status();
  if (read->vertices.empty()) {
    read->offsets.clear();  // every function is empty: Function() is not called on it
    read->offsets.shrink_to_fit();
  }
  auto tile = std::make_shared<const PdsmTile>(*std::move(read));
  absl::MutexLock lock(&mu_);
  ++tiles_read_;
  auto [it, added] = entries_.try_emplace(key);
  if (!added) {  // another thread read it meanwhile
    lru_.splice(lru_.begin(), lru_, it->second.lru);
    return it->second.tile;
  }
  lru_.push_front(key);
  it->second = Entry{tile, TileBytes(*tile), lru_.begin()};
  bytes_held_ += it->second.bytes;
  while (bytes_held_ > budget_bytes_ && lru_.size() > 1) {
    const auto last = entries_.find(lru_.back());
    bytes_held_ -= last->second.bytes;
    entries_.erase(last);
    lru_.pop_back();
  }
  return tile;
}

absl::StatusOr<double> PdsmTileCache::Attenuation(int part, const glm::dvec3& p_world) {
  const PdsmHeader& header = reader_.headers().at(part);
  const std::optional<PdsmPoint> point = header.geometry.Locate(p_world);
  if (!point) return std::numeric_limits<double>::quiet_NaN();
  const int size = header.tile_size;
  absl::Status status;
  // The tiles of the four pixels, held for the whole lookup (a refined pixel's spans are read
  // after its neighbours are fetched); mostly one tile.
  std::shared_ptr<const PdsmTile> held[4];
  int count = 0;
  const double a =
      BilinearAttenuationOf(header.geometry, *point, [&](int x, int y) -> std::span<const Vertex> {
        const PdsmTile* tile = nullptr;
        for (int k = 0; k < count && tile == nullptr; ++k) {
          const PdsmTile& t = *held[k];
          if (x >= t.x0 && x < t.x0 + t.width && y >= t.y0 && y < t.y0 + t.height) tile = &t;
        }
        if (tile == nullptr) {
          absl::StatusOr<std::shared_ptr<const PdsmTile>> got = Tile(part, x / size, y / size);
          if (!got.ok()) {
            status = got.status();
            return {};
          }
          held[count] = *std::move(got);
          tile = held[count++].get();
        }
        if (tile->vertices.empty()) return {};
        return tile->Function(x - tile->x0, y - tile->y0);
      });
  if (!status.ok()) return status;
  return a;
}

int64_t TileIndexAt(const PdsmHeader& header, const glm::dvec3& p_world) {
  const std::optional<PdsmPoint> point = header.geometry.Locate(p_world);
  if (!point) return -1;
  const PdsmGeometry& g = header.geometry;
  const int x = std::clamp(static_cast<int>(point->px), 0, g.width - 1);
  const int y = std::clamp(static_cast<int>(point->py), 0, g.height - 1);
  const int64_t tiles_x = (g.width + header.tile_size - 1) / header.tile_size;
  return int64_t{y / header.tile_size} * tiles_x + x / header.tile_size;
}

int64_t PdsmTileCache::TileKey(int part, const glm::dvec3& p_world) const {
  return TileIndexAt(reader_.headers().at(part), p_world);
}

absl::StatusOr<std::vector<double>> AttenuationAt(PdsmTileCache& cache,
                                                  std::span<const PdsmLightParts> lights,
                                                  std::span<const glm::dvec3> points_world) {
  const std::vector<PdsmHeader>& headers = cache.reader().headers();
  std::vector<int64_t> keys(points_world.size());
  std::vector<size_t> order(points_world.size());
  for (size_t k = 0; k < points_world.size(); ++k) {
    keys[k] = cache.TileKey(lights[0].parts[0], points_world[k]);
    order[k] = k;
  }
  std::stable_sort(order.begin(), order.end(),
                   [&keys](size_t a, size_t b) { return keys[a] < keys[b]; });
  std::vector<double> values(points_world.size() * lights.size());
  for (const size_t k : order) {
    for (size_t l = 0; l < lights.size(); ++l) {
      const int part = PartAt(headers, lights[l], points_world[k]);
      absl::StatusOr<double> a = cache.Attenuation(part, points_world[k]);
      if (!a.ok()) return a.status();
      values[k * lights.size() + l] = *a;
    }
  }
  return values;
}

int64_t PdsmTileCache::bytes_held() const {
  absl::MutexLock lock(&mu_);
  return bytes_held_;
}

int64_t PdsmTileCache::tiles_read() const {
  absl::MutexLock lock(&mu_);
  return tiles_read_;
}

}  // namespace pdsm
