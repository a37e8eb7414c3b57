// The finished tiles of one PDSM part, encoded (tile_chunk.h) on the threads that finished
// them and kept until the part is written: how the local bake writes its file, as the
// coordinator does from its tile files (server/stored_job.h), so that compressing runs on
// every bake thread instead of under the writer's lock, and a tile without a vertex (most of
// a sparse world's) is not compressed at all (EmptyTileChunks).
//
// The chunks go, in the order they come, to one unnamed scratch file (core/util/file_system.h:
// gone however the process ends) beside the output; memory holds 16 bytes a tile. Tiles come
// in any order; WriteTo hands them to the part's writer in the grid's order, and the file's
// bytes are those PdsmWriter::WriteTile would write (PdsmTileChunkTest). Thread-safe.
#ifndef PDSM_CORE_PDSM_ENCODED_TILE_STORE_H_
#define PDSM_CORE_PDSM_ENCODED_TILE_STORE_H_

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "absl/base/thread_annotations.h"
#include "absl/status/status.h"
#include "absl/synchronization/mutex.h"
#include "core/pdsm/pdsm_file.h"
#include "core/pdsm/pdsm_image.h"
#include "core/pdsm/tile_chunk.h"
#include "core/util/file_system.h"

namespace pdsm {

struct TileGrid;

class EncodedTileStore {
 public:
  // The grid of `header` (its size and tile size), for the part written to `output_path`:
  // the scratch file goes in its folder (made at the first tile with a vertex), and errors
  // name it. `fs` null: the real file system; it outlives this.
  EncodedTileStore(const PdsmHeader& header, std::string output_path, FileSystem* fs = nullptr);

  // Encodes `tile` and keeps it. INVALID_ARGUMENT for a tile that is not a cell of the grid,
  // or is put twice; the encoder's errors (a function a PDSM cannot hold) and the scratch
  // file's (RESOURCE_EXHAUSTED for a full disk, …), which are sticky: every later call
  // returns the first, and the file is not touched again.
  absl::Status Put(const PdsmTile& tile);
  // The same for a tile without a vertex at (x0, y0), its size the grid's cell there, carrying
  // `samples`: nothing to encode or assemble.
  absl::Status PutWithoutVertices(int x0, int y0, int samples);

  // The stored tile whose corner is (x0, y0), decoded. FAILED_PRECONDITION when it was never
  // stored; the scratch file's and the decoder's errors.
  absl::StatusOr<PdsmTile> Get(int x0, int y0);
  // Puts `tile` in place of the stored tile of its cell (adaptive resolution's refined pixels:
  // worker/local_bake.cc, RefineLight); the old chunk's bytes stay in the scratch file unused.
  // FAILED_PRECONDITION when none was stored; otherwise as Put.
  absl::Status Replace(const PdsmTile& tile);

  // Writes every tile into `writer` (PdsmWriter::WriteEncodedTiles), which must be a writer of
  // this grid with no tile written. FAILED_PRECONDITION naming the first missing tile; the
  // scratch file's and the writer's errors.
  absl::Status WriteTo(PdsmWriter* writer);

  // What this holds in memory per tile of its grid (a coordinator counts it: server/plan_budget.h).
  static constexpr int64_t kHeldBytesPerTile = 24;  // sizeof(Place), asserted in the .cc

 private:
  // Where tile i is: its chunk at [offset, offset + size) of the scratch file, or, with
  // size 0, a tile without a vertex (its chunk is empty_'s).
  struct Place {
    uint64_t offset = 0;
    uint32_t size = 0;
    int32_t samples = 0;
    bool present = false;
  };

  // `status` with the output's path appended.
  absl::Status ForOutput(const absl::Status& status) const;
  // The index of the cell whose corner is (x0, y0) and whose size is width x height, or
  // INVALID_ARGUMENT.
  absl::StatusOr<size_t> CellIndex(int x0, int y0, int width, int height) const;
  // Keeps tile `index` at `place` (its chunk, if any, appended to the scratch file): a new
  // tile, or with `replace` one in place of the stored one. Errors of the scratch file name the
  // output.
  absl::Status Keep(size_t index, Place place, const std::string& chunk, int x0, int y0,
                    bool replace = false);
  // Put's encoding of `tile` for cell `index`.
  absl::Status Encode(const PdsmTile& tile, size_t index, bool replace);

  // The grid (core/pdsm/pdsm_exr_tiles.h, which OpenEXR's headers come with: kept out of
  // this header, which the worker includes).
  TileGrid Grid() const;

  const int width_, height_, tile_size_;
  const std::string output_path_;
  FileSystem* const fs_;
  EmptyTileChunks empty_;  // in tiles of the grid's size

  absl::Mutex mu_;
  std::vector<Place> places_ ABSL_GUARDED_BY(mu_);
  std::unique_ptr<ScratchFile> scratch_ ABSL_GUARDED_BY(mu_);
  uint64_t scratch_end_ ABSL_GUARDED_BY(mu_) = 0;
  absl::Status error_ ABSL_GUARDED_BY(mu_);  // sticky: after a failure nothing more is written
};

}  // namespace pdsm

#endif  // PDSM_CORE_PDSM_ENCODED_TILE_STORE_H_
