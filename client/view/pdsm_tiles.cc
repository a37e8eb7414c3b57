#include "client/view/pdsm_tiles.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "absl/strings/str_cat.h"
#include "core/pdsm/pdsm_file.h"
#include "core/pdsm/pdsm_query.h"

namespace pdsm::view {
namespace {

int TileCount(int pixels, int tile_size) { return (pixels + tile_size - 1) / tile_size; }

// The reader's messages usually name the file already; make sure they do.
absl::Status NamingFile(const absl::Status& status, const std::string& path) {
  const std::string message(status.message());
  if (message.find(path) != std::string::npos) return status;
  return absl::Status(status.code(), absl::StrCat("--pdsm ", path, ": ", message));
}

}  // namespace

absl::StatusOr<std::shared_ptr<PdsmTiles>> PdsmTiles::OpenFile(const std::string& path,
                                                               const std::string& light,
                                                               int64_t cache_bytes) {
  absl::StatusOr<PdsmReader> reader = PdsmReader::Open(path);
  if (!reader.ok()) return NamingFile(reader.status(), path);
  absl::StatusOr<int> part = reader->FindLight(light);
  if (!part.ok()) return NamingFile(part.status(), path);
  return FromReader(*std::move(reader), *part, cache_bytes);
}

std::shared_ptr<PdsmTiles> PdsmTiles::FromReader(PdsmReader reader, int part, int64_t cache_bytes) {
  std::shared_ptr<PdsmTiles> tiles(new PdsmTiles());
  tiles->header_ = reader.headers().at(part);
  tiles->part_ = part;
  tiles->cache_ = std::make_unique<PdsmTileCache>(std::move(reader), cache_bytes);
  const int size = std::max(tiles->header_.tile_size, 1);
  tiles->tiles_x_ = TileCount(tiles->header_.geometry.width, size);
  tiles->tiles_y_ = TileCount(tiles->header_.geometry.height, size);
  return tiles;
}

std::shared_ptr<PdsmTiles> PdsmTiles::FromImage(PdsmImage image, std::vector<uint8_t> pending) {
  std::shared_ptr<PdsmTiles> tiles(new PdsmTiles());
  tiles->header_ = image.header;
  // An image made in memory (tests) may leave tile_size unset: one tile then.
  if (tiles->header_.tile_size <= 0) {
    tiles->header_.tile_size = std::max(image.header.geometry.width, image.header.geometry.height);
  }
  const PdsmGeometry& g = tiles->header_.geometry;
  const int size = tiles->header_.tile_size;
  tiles->tiles_x_ = TileCount(g.width, size);
  tiles->tiles_y_ = TileCount(g.height, size);
  if (std::any_of(pending.begin(), pending.end(), [](uint8_t flag) { return flag != 0; })) {
    tiles->pending_tiles_.assign(static_cast<size_t>(tiles->tiles_x_) * tiles->tiles_y_, 0);
    for (int y = 0; y < g.height; ++y) {
      for (int x = 0; x < g.width; ++x) {
        if (pending[static_cast<size_t>(y) * g.width + x] != 0) {
          tiles->pending_tiles_[static_cast<size_t>(y / size) * tiles->tiles_x_ + x / size] = 1;
        }
      }
    }
  }
  tiles->image_ = std::move(image);
  return tiles;
}

bool PdsmTiles::TilePending(int tile_x, int tile_y) const {
  return !pending_tiles_.empty() &&
         pending_tiles_[static_cast<size_t>(tile_y) * tiles_x_ + tile_x] != 0;
}

absl::StatusOr<std::shared_ptr<const PdsmTile>> PdsmTiles::Tile(int tile_x, int tile_y) {
  if (TilePending(tile_x, tile_y)) return nullptr;
  if (cache_) return cache_->Tile(part_, tile_x, tile_y);
  const PdsmGeometry& g = header_.geometry;
  const int size = header_.tile_size;
  auto tile = std::make_shared<PdsmTile>();
  tile->x0 = tile_x * size;
  tile->y0 = tile_y * size;
  tile->width = std::min(size, g.width - tile->x0);
  tile->height = std::min(size, g.height - tile->y0);
  tile->offsets.reserve(static_cast<size_t>(tile->width) * tile->height + 1);
  tile->offsets.push_back(0);
  for (int y = 0; y < tile->height; ++y) {
    for (int x = 0; x < tile->width; ++x) {
      const std::span<const Vertex> f = image_->Function(tile->x0 + x, tile->y0 + y);
      tile->vertices.insert(tile->vertices.end(), f.begin(), f.end());
      tile->offsets.push_back(tile->vertices.size());
    }
  }
  return tile;
}

absl::StatusOr<std::optional<double>> PdsmTiles::Attenuation(const glm::dvec3& p_world) {
  const PdsmGeometry& g = header_.geometry;
  const std::optional<PdsmPoint> point = g.Locate(p_world);
  if (!point) return std::optional<double>(std::numeric_limits<double>::quiet_NaN());
  if (!pending_tiles_.empty()) {
    // The same neighbours BilinearAttenuationOf blends, clamped at the border.
    const int x0 = static_cast<int>(std::floor(point->px - 0.5));
    const int y0 = static_cast<int>(std::floor(point->py - 0.5));
    const int size = header_.tile_size;
    for (int y : {std::clamp(y0, 0, g.height - 1), std::clamp(y0 + 1, 0, g.height - 1)}) {
      for (int x : {std::clamp(x0, 0, g.width - 1), std::clamp(x0 + 1, 0, g.width - 1)}) {
        if (TilePending(x / size, y / size)) return std::optional<double>();
      }
    }
  }
  if (cache_) {
    absl::StatusOr<double> a = cache_->Attenuation(part_, p_world);
    if (!a.ok()) return a.status();
    return std::optional<double>(*a);
  }
  return std::optional<double>(BilinearAttenuation(*image_, *point));
}

absl::StatusOr<std::vector<std::optional<double>>> PdsmTiles::AttenuationAt(
    std::span<const glm::dvec3> points_world) {
  std::vector<int64_t> keys(points_world.size());
  std::vector<size_t> order(points_world.size());
  for (size_t k = 0; k < points_world.size(); ++k) {
    order[k] = k;
    keys[k] = TileIndexAt(header_, points_world[k]);
  }
  std::stable_sort(order.begin(), order.end(),
                   [&keys](size_t a, size_t b) { return keys[a] < keys[b]; });
  std::vector<std::optional<double>> values(points_world.size());
  for (const size_t k : order) {
    absl::StatusOr<std::optional<double>> a = Attenuation(points_world[k]);
    if (!a.ok()) return a.status();
    values[k] = *a;
  }
  return values;
}

}  // namespace pdsm::view
