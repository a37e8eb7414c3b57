// One tile of a PDSM as the file stores it: OpenEXR's compressed chunk of a deep tile (its
// coordinates, sizes, sample-count table and ZIPS-compressed Z and attenuation), so that a
// tile compressed once, where it was finished, is copied into the file without being decoded
// or compressed again (PdsmWriter::WriteEncodedTiles). The coordinator keeps its finished
// tiles this way (core/pipeline/tile_file.h): a fifth of the raw vertices' bytes, and the
// job's file assembled at its end by copying instead of compressing.
//
// A chunk made here is tile-local: encoded as the only tile of an image whose data window is
// the tile itself, so its tile coordinates are (0, 0). OpenEXR's compressed bytes depend only
// on the tile's own pixels (its width, height, counts and values), so a chunk moved to tile
// (dx, dy) of a grid (RelocateTileChunk) is byte for byte what DeepTiledOutputFile writes
// for that tile there: PdsmTileChunkTest checks it against PdsmWriter.
#ifndef PDSM_CORE_PDSM_TILE_CHUNK_H_
#define PDSM_CORE_PDSM_TILE_CHUNK_H_

#include <string>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "core/pdsm/pdsm_image.h"

namespace pdsm {

// A finished tile, encoded: where it is, how many light samples stand behind it (adaptive
// bakes; 0 otherwise) and its tile-local chunk (empty for a tile of no pixel).
struct EncodedTile {
  int x0 = 0, y0 = 0, width = 0, height = 0;
  int samples = 0;
  std::string chunk;
};

// The tile's chunk. INVALID_ARGUMENT when the tile's offsets do not span its vertices, or a
// function is not one a PDSM holds (CheckTileFunctions). A tile of no pixel has an empty chunk.
absl::StatusOr<EncodedTile> EncodeTileChunk(const PdsmTile& tile);

// The tile back, exactly. DATA_LOSS naming `label` when the chunk is not one of such a tile
// (OpenEXR's decoding failed, counts beyond kMaxVerticesPerTile, functions a PDSM cannot hold).
absl::StatusOr<PdsmTile> DecodeTileChunk(const EncodedTile& tile, absl::string_view label);

// The chunk with its tile coordinates set to (dx, dy) (level 0). REQUIRES: a chunk made by
// EncodeTileChunk (at least its 16 bytes of coordinates).
std::string RelocateTileChunk(std::string chunk, int dx, int dy);

}  // namespace pdsm

#endif  // PDSM_CORE_PDSM_TILE_CHUNK_H_
