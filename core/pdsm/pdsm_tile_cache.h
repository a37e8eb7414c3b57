// A PDSM file's tiles read on demand and kept within a memory budget (issue #12, "consumers
// read only what they need"): `pdsm query` and the coordinator's QueryAttenuation answer points
// on a map of any size with memory bounded by the budget, not by the map. The answers are the
// same, bit for bit, as from the whole map read at once (QueryAttenuation in pdsm_query.h).
//
// Tiles are kept least recently used first out. A tile with no vertex (all lit: most of a
// large world's map) is kept as a few bytes. Thread-safe: lookups from any thread; a tile
// missing is read under the reader's own lock, outside the cache's.
#ifndef PDSM_CORE_PDSM_PDSM_TILE_CACHE_H_
#define PDSM_CORE_PDSM_PDSM_TILE_CACHE_H_

#include <cstdint>
#include <list>
#include <memory>
#include <span>
#include <unordered_map>
#include <vector>

#include <glm/glm.hpp>

#include "absl/base/thread_annotations.h"
#include "absl/status/statusor.h"
#include "absl/synchronization/mutex.h"
#include "core/pdsm/pdsm_file.h"
#include "core/pdsm/pdsm_image.h"
#include "core/pdsm/pdsm_lights.h"

namespace pdsm {

// `pdsm query --cache-mib` unless set.
inline constexpr int64_t kDefaultTileCacheBytes = int64_t{256} << 20;

class PdsmTileCache {
 public:
  // `budget_bytes`: the most the kept tiles may hold (at least one tile is kept, whatever it
  // holds).
  PdsmTileCache(PdsmReader reader, int64_t budget_bytes);
  PdsmTileCache(const PdsmTileCache&) = delete;
  PdsmTileCache& operator=(const PdsmTileCache&) = delete;

  const PdsmReader& reader() const { return reader_; }

  // Tile (tile_x, tile_y) of part `part`; errors as PdsmReader::ReadTile's.
  absl::StatusOr<std::shared_ptr<const PdsmTile>> Tile(int part, int tile_x, int tile_y);

  // The attenuation at `p_world` from part `part`: QueryAttenuation's answer (NaN outside the
  // part's frustum). Errors: reading a tile.
  absl::StatusOr<double> Attenuation(int part, const glm::dvec3& p_world);

  // The tile of part `part` whose pixel holds `p_world`, as one key that orders points so
  // that neighbours share tiles; -1 outside the frustum.
  int64_t TileKey(int part, const glm::dvec3& p_world) const;

  int64_t bytes_held() const;
  int64_t tiles_read() const;  // since construction, re-reads of evicted tiles included

 private:
  struct Entry {
    std::shared_ptr<const PdsmTile> tile;
    int64_t bytes = 0;
    std::list<uint64_t>::iterator lru;
  };
  static uint64_t Key(int part, int tile_x, int tile_y);

  PdsmReader reader_;
  const int64_t budget_bytes_;
  mutable absl::Mutex mu_;
  std::unordered_map<uint64_t, Entry> entries_ ABSL_GUARDED_BY(mu_);
  std::list<uint64_t> lru_ ABSL_GUARDED_BY(mu_);  // most recently used first
  int64_t bytes_held_ ABSL_GUARDED_BY(mu_) = 0;
  int64_t tiles_read_ ABSL_GUARDED_BY(mu_) = 0;
};

// The row-major index of the tile of `header`'s map whose pixel holds `p_world`; -1 outside
// the frustum. Ordering points by it makes neighbours in the map share a tile read.
int64_t TileIndexAt(const PdsmHeader& header, const glm::dvec3& p_world);

// The attenuation at each of `points_world` for each of `lights` (core/pdsm/pdsm_lights.h: a
// sphere's value from the face that holds the point), point-major (point k's value for
// lights[l] at k * lights.size() + l). The points are answered in the order of their tiles (of
// lights[0]'s first part), so that neighbours in the map share a read whatever their order here.
// REQUIRES: lights non-empty, each of parts of the cache's file. Errors: reading a tile.
absl::StatusOr<std::vector<double>> AttenuationAt(PdsmTileCache& cache,
                                                  std::span<const PdsmLightParts> lights,
                                                  std::span<const glm::dvec3> points_world);

}  // namespace pdsm

#endif  // PDSM_CORE_PDSM_PDSM_TILE_CACHE_H_
