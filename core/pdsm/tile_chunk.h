// One tile of a PDSM as the file stores it: OpenEXR's compressed chunk of a deep tile (its
// coordinates, sizes, sample-count table and ZIPS-compressed Z and attenuation), so that a
// tile compressed once, where it was finished, is copied into the file without being decoded
// or compressed again (PdsmWriter::WriteEncodedTiles). The coordinator keeps its finished
// tiles this way (core/pipeline/tile_file.h): a fifth of the raw vertices' bytes, and the
// job's file assembled at its end by copying instead of compressing.
//
// A chunk made here is tile-local: encoded as tile (0, 0) of an image whose data window is the
// tile itself, in tiles of the grid's tile size (a partial tile stays partial: OpenEXR sizes
// its compression by the tile size, so that is part of the bytes). OpenEXR's compressed bytes
// then depend only on the tile's pixels and the tile size, so a chunk moved to tile (dx, dy) of
// a grid (RelocateTileChunk) is byte for byte what DeepTiledOutputFile writes for that tile
// there: PdsmTileChunkTest checks it against PdsmWriter, at every small size.
#ifndef PDSM_CORE_PDSM_TILE_CHUNK_H_
#define PDSM_CORE_PDSM_TILE_CHUNK_H_

#include <map>
#include <string>
#include <utility>

#include "absl/base/thread_annotations.h"
#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "absl/synchronization/mutex.h"
#include "core/pdsm/pdsm_image.h"

namespace pdsm {

// A finished tile, encoded: where it is, how many light samples stand behind it (adaptive
// bakes; 0 otherwise) and its tile-local chunk (empty for a tile of no pixel).
struct EncodedTile {
  int x0 = 0, y0 = 0, width = 0, height = 0;
  int samples = 0;
  int tile_size = 0;  // the grid's, which the chunk was encoded with
  std::string chunk;
};

// The tile's chunk, as a cell of a grid of `tile_size`-pixel tiles. INVALID_ARGUMENT when the
// tile is larger than that, its offsets do not span its vertices, or a function is not one a
// PDSM holds (CheckTileFunctions). A tile of no pixel has an empty chunk.
absl::StatusOr<EncodedTile> EncodeTileChunk(const PdsmTile& tile, int tile_size);

// The tile back, exactly. DATA_LOSS naming `label` when the chunk is not one of such a tile
// (OpenEXR's decoding failed, counts beyond kMaxVerticesPerTile, functions a PDSM cannot hold).
absl::StatusOr<PdsmTile> DecodeTileChunk(const EncodedTile& tile, absl::string_view label);

// The chunk with its tile coordinates set to (dx, dy) (level 0). REQUIRES: a chunk made by
// EncodeTileChunk (at least its 16 bytes of coordinates).
std::string RelocateTileChunk(std::string chunk, int dx, int dy);

// Tiles without a vertex (all lit: most tiles of a sparse world) encode to the same chunk for
// one size, wherever they are: each size is encoded once. Thread-safe.
class EmptyTileChunks {
 public:
  explicit EmptyTileChunks(int tile_size) : tile_size_(tile_size) {}

  // The chunk of a width x height tile without a vertex, in tiles of the tile size. Errors as
  // EncodeTileChunk's.
  absl::StatusOr<std::string> Chunk(int width, int height);
  // The whole encoded tile at (x0, y0) of that size, holding `samples` (EncodedTile::samples):
  // what a writer copies for a tile without a vertex. Errors as Chunk's.
  absl::StatusOr<EncodedTile> Tile(int x0, int y0, int width, int height, int samples);

 private:
  const int tile_size_;
  absl::Mutex mu_;
  std::map<std::pair<int, int>, std::string> by_size_ ABSL_GUARDED_BY(mu_);
};

}  // namespace pdsm

#endif  // PDSM_CORE_PDSM_TILE_CHUNK_H_
