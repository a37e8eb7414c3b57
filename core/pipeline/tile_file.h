// One finished (assembled, compressed) tile as bytes: how the coordinator's tile log keeps it
// (server/tile_log.h), so that a restarted coordinator resumes a job without recomputing the
// tiles it had finished, and how FetchTile sends it. (Until 2026-12-06 each was a file of its
// own; the coordinator takes such files into the log when it resumes their job.)
//
// Layout, all integers little-endian (version 3):
//   char[8]  magic "PDSMTILE"
//   uint32   version (kTileFileVersion)
//   int32    x0, y0, width, height
//   int32    samples         the tile's light samples (adaptive bakes); 0 in a fixed-count bake
//   int32    tile_size       the grid's tile size, which the chunk was encoded with
//   uint64   chunk_bytes
//   char     chunk[chunk_bytes]   the tile as the PDSM file stores it: OpenEXR's compressed
//                            deep tile, tile-local (core/pdsm/tile_chunk.h), so that the job's
//                            file is assembled by copying it (PdsmWriter::WriteEncodedTiles)
//   uint64   checksum: FNV-1a 64 of every byte before it
// Versions 1 and 2, written by earlier builds, are still read (a job survives an upgrade of its
// coordinator): after x0..height they hold uint64 offset_count (= width * height + 1), uint64
// vertex_count, uint64 offsets[offset_count], float32 z, a per vertex (IEEE-754 bits), version
// 2 an int32 samples, then the same checksum.
#ifndef PDSM_CORE_PIPELINE_TILE_FILE_H_
#define PDSM_CORE_PIPELINE_TILE_FILE_H_

#include <cstdint>
#include <string>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/pdsm/pdsm_image.h"
#include "core/pdsm/tile_chunk.h"

namespace pdsm {

inline constexpr uint32_t kTileFileVersion = 3;

// `tile` as a tile file (version 3). `tile_size`: the grid's (tile_chunk.h). INVALID_ARGUMENT
// naming `label` when the tile's offsets are not width * height + 1 nondecreasing values from
// 0 to the vertex count, width or height is negative, or a function is not one a PDSM holds
// (CheckTileFunctions).
absl::StatusOr<std::string> EncodeTileFile(const PdsmTile& tile, int tile_size,
                                           const std::string& label);

// The tile of a tile file's bytes (from the tile log, or received over the network:
// FetchTile); `label` names them in errors. Sizes are checked against the bytes' length before
// anything is allocated from them, so corrupt bytes cost no more memory than their own size.
// DATA_LOSS naming `label` when they are not a tile file, truncated, inconsistent (offsets) or
// fail their checksum; FAILED_PRECONDITION for a version newer than this build reads.
absl::StatusOr<PdsmTile> DecodeTileFile(const std::string& bytes, const std::string& label);

// Whether `bytes` are a whole tile file this build reads: DecodeTileFile's errors, without
// decoding the tile.
absl::Status CheckTileFileBytes(const std::string& bytes, const std::string& label);

// The tile as the PDSM file will hold it, without decoding it (bytes of version 1 or 2 are
// encoded now, in tiles of `tile_size`). Errors as DecodeTileFile's.
absl::StatusOr<EncodedTile> DecodeTileChunkFile(const std::string& bytes, const std::string& label,
                                                int tile_size);

// `tile` in the layout of versions 1 and 2, as earlier builds wrote it: for tests that this
// build still reads them.
std::string EncodeEarlierTileFile(const PdsmTile& tile);

}  // namespace pdsm

#endif  // PDSM_CORE_PIPELINE_TILE_FILE_H_
