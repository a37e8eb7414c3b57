// One finished (assembled, compressed) tile on the coordinator's disk, so that a restarted
// coordinator resumes a job without recomputing the tiles it had finished.
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
#include "core/util/file_system.h"

namespace pdsm {

inline constexpr uint32_t kTileFileVersion = 3;

// Writes `tile` to `path`, crash-safe, through WriteFileAtomically (core/util/atomic_file.h):
// the bytes go to a unique "<path>.tmp-XXXXXX", are synced, the file is renamed onto `path`
// and the folder is synced. So `path` holds either its old content or the whole new tile,
// never part of one, and concurrent writers of one tile never share a temporary file. On
// error no temporary file is left; a crash can leave one, which no reader opens.
// Errors: INVALID_ARGUMENT when the tile's offsets are not width * height + 1 nondecreasing
// values from 0 to the vertex count, width or height is negative, or a function is not one a
// PDSM holds (CheckTileFunctions); otherwise the errno
// status of the failing step (e.g. RESOURCE_EXHAUSTED for a full disk), naming the path.
// `fs` null means FileSystem::Default().
// `tile_size`: the grid's (tile_chunk.h).
absl::Status WriteTileFile(const std::string& path, const PdsmTile& tile, int tile_size,
                           FileSystem* fs = nullptr);

// The bytes WriteTileFile writes (version 3), for a store of its own (server/tile_log.h).
// Errors as WriteTileFile's before it writes, naming `label`.
absl::StatusOr<std::string> EncodeTileFile(const PdsmTile& tile, int tile_size,
                                           const std::string& label);

// Reads a tile written by WriteTileFile. Sizes in the file are checked against the file's
// length before anything is allocated from them, so a corrupt file costs no more memory than
// its own size. Errors: NOT_FOUND (no file); DATA_LOSS naming the file when it is not a tile
// file, truncated, inconsistent (offsets) or fails its checksum; FAILED_PRECONDITION for a
// version newer than this build reads.
absl::StatusOr<PdsmTile> ReadTileFile(const std::string& path);

// The same from the file's bytes (received over the network: FetchTile); `label` names them
// in errors.
absl::StatusOr<PdsmTile> DecodeTileFile(const std::string& bytes, const std::string& label);

// The tile as the PDSM file will hold it, without decoding it (a file of version 1 or 2 is
// encoded now, in tiles of `tile_size`). Errors as ReadTileFile's.
absl::StatusOr<EncodedTile> ReadTileChunk(const std::string& path, int tile_size);

// Whether `bytes` are a whole tile file this build reads: the errors ReadTileFile gives for
// them, without decoding the tile.
absl::Status CheckTileFileBytes(const std::string& bytes, const std::string& label);

// ReadTileChunk from a tile file's bytes (of any version); `label` names them in errors.
absl::StatusOr<EncodedTile> DecodeTileChunkFile(const std::string& bytes, const std::string& label,
                                                int tile_size);

// `tile` in the layout of versions 1 and 2, as earlier builds wrote it: for tests that this
// build still reads them.
std::string EncodeEarlierTileFile(const PdsmTile& tile);

}  // namespace pdsm

#endif  // PDSM_CORE_PIPELINE_TILE_FILE_H_
