// One finished (assembled, compressed) tile on the coordinator's disk, so that a restarted
// coordinator resumes a job without recomputing the tiles it had finished.
//
// Layout, all integers little-endian, floats as their IEEE-754 bits (stored exactly):
//   char[8]  magic "PDSMTILE"
//   uint32   version (kTileFileVersion)
//   int32    x0, y0, width, height
//   uint64   offset_count   (= width * height + 1)
//   uint64   vertex_count   (= the last offset)
//   uint64   offsets[offset_count]   (start at 0, nondecreasing)
//   float32  z, a            per vertex, vertex_count times
//   int32    samples         version 2 only: the tile's light samples (adaptive bakes); a
//                            tile with samples == 0 (fixed-count bake) is written as version 1
//   uint64   checksum: FNV-1a 64 of every byte before it
#ifndef PDSM_CORE_PIPELINE_TILE_FILE_H_
#define PDSM_CORE_PIPELINE_TILE_FILE_H_

#include <cstdint>
#include <string>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/pdsm/pdsm_image.h"
#include "core/util/file_system.h"

namespace pdsm {

inline constexpr uint32_t kTileFileVersion = 2;

// Writes `tile` to `path`, crash-safe, through WriteFileAtomically (core/util/atomic_file.h):
// the bytes go to a unique "<path>.tmp-XXXXXX", are synced, the file is renamed onto `path`
// and the folder is synced. So `path` holds either its old content or the whole new tile,
// never part of one, and concurrent writers of one tile never share a temporary file. On
// error no temporary file is left; a crash can leave one, which no reader opens.
// Errors: INVALID_ARGUMENT when the tile's offsets are not width * height + 1 nondecreasing
// values from 0 to the vertex count, or width or height is negative; otherwise the errno
// status of the failing step (e.g. RESOURCE_EXHAUSTED for a full disk), naming the path.
// `fs` null means FileSystem::Default().
absl::Status WriteTileFile(const std::string& path, const PdsmTile& tile, FileSystem* fs = nullptr);

// Reads a tile written by WriteTileFile. Sizes in the file are checked against the file's
// length before anything is allocated from them, so a corrupt file costs no more memory than
// its own size. Errors: NOT_FOUND (no file); DATA_LOSS naming the file when it is not a tile
// file, truncated, inconsistent (offsets) or fails its checksum; FAILED_PRECONDITION for a
// version newer than this build reads.
absl::StatusOr<PdsmTile> ReadTileFile(const std::string& path);

// The same from the file's bytes (received over the network: FetchTile); `label` names them
// in errors.
absl::StatusOr<PdsmTile> DecodeTileFile(const std::string& bytes, const std::string& label);

}  // namespace pdsm

#endif  // PDSM_CORE_PIPELINE_TILE_FILE_H_
