// Where the viewer reads a PDSM's functions from (issue #12, "consumers read only what they
// need"): tiles on demand, either from a file through a bounded cache (a map of any size:
// memory is the cache's budget, not the map's size), or cut from a whole map held in memory
// (a job followed while it runs, whose unfinished tiles are pending).
//
// Both give the same functions, bit for bit, as the whole map read at once; Attenuation is
// QueryAttenuation's answer (core/pdsm/pdsm_query.h). Thread safety: Tile and Attenuation may
// be called from any thread (the file's cache locks; the image is only read).
#ifndef PDSM_CLIENT_VIEW_PDSM_TILES_H_
#define PDSM_CLIENT_VIEW_PDSM_TILES_H_

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "absl/status/statusor.h"
#include "core/pdsm/pdsm_file.h"
#include "core/pdsm/pdsm_image.h"
#include "core/pdsm/pdsm_tile_cache.h"

namespace pdsm::view {

class PdsmTiles {
 public:
  // Light `light` of the PDSM file at `path` (empty: its only light), its tiles read when
  // first asked for and kept within `cache_bytes`. Errors name the file: NOT_FOUND (also: no
  // such light), DATA_LOSS (corrupt or not a PDSM), FAILED_PRECONDITION (a format version this
  // build does not read, or several lights and no `light`).
  static absl::StatusOr<std::shared_ptr<PdsmTiles>> OpenFile(const std::string& path,
                                                             const std::string& light,
                                                             int64_t cache_bytes);
  // Part `part` of an open file (REQUIRES: a part of it), as OpenFile.
  static std::shared_ptr<PdsmTiles> FromReader(PdsmReader reader, int part, int64_t cache_bytes);
  // A whole map in memory; `pending` (empty, or one flag per pixel) marks pixels not baked
  // yet. A tile is pending when any of its pixels is (tiles finish whole).
  static std::shared_ptr<PdsmTiles> FromImage(PdsmImage image, std::vector<uint8_t> pending = {});

  const PdsmHeader& header() const { return header_; }
  int tiles_x() const { return tiles_x_; }
  int tiles_y() const { return tiles_y_; }

  // Tile (tile_x, tile_y): nullptr while it is pending. A tile without any vertex may hold no
  // offsets (every function empty). Errors: reading the file (they name it).
  absl::StatusOr<std::shared_ptr<const PdsmTile>> Tile(int tile_x, int tile_y);
  bool TilePending(int tile_x, int tile_y) const;
  bool any_pending() const { return !pending_tiles_.empty(); }

  // QueryAttenuation's answer at `p_world` (NaN outside the frustum); nullopt when a pixel it
  // blends is pending. Errors: reading a tile.
  absl::StatusOr<std::optional<double>> Attenuation(const glm::dvec3& p_world);

  // Attenuation at each point, answered in the order of their tiles so that a bounded cache
  // reads each tile once however the points are ordered (their answers in their own order).
  absl::StatusOr<std::vector<std::optional<double>>> AttenuationAt(
      std::span<const glm::dvec3> points_world);

  // Tiles read from the file so far (re-reads after eviction included); 0 for an image.
  int64_t tiles_read() const { return cache_ ? cache_->tiles_read() : 0; }
  int64_t cache_bytes_held() const { return cache_ ? cache_->bytes_held() : 0; }

 private:
  PdsmTiles() = default;

  PdsmHeader header_;
  int tiles_x_ = 0, tiles_y_ = 0;
  // One of the two: the file's cache (and its part), or the image.
  std::unique_ptr<PdsmTileCache> cache_;
  int part_ = 0;
  std::optional<PdsmImage> image_;
  std::vector<uint8_t> pending_tiles_;  // per tile, row-major; empty: none pending
};

}  // namespace pdsm::view

#endif  // PDSM_CLIENT_VIEW_PDSM_TILES_H_
