// The tiles that reach a PDSM writer before their turn. A file's bytes must not depend on the
// order tiles finish in, so the writer (pdsm_file.h) emits them in row-major order and keeps
// the ones that come early here. Bakes finish tiles far out of order (the engine stores every
// tile no caster reaches first, then the rest as their groups finish), so at large map sizes
// most of a map can be early at once (issue #12 item 5: a 16384² sparse world held 540 MiB
// here). The buffer bounds that:
// - a tile with no vertex (all lit: most of a sparse world) is kept as its rectangle alone;
// - the other tiles are kept in memory up to a byte budget; past it, each newcomer goes to a
//   scratch file (core/util/file_system.h: no name, nothing left however the process ends)
//   and is read back, bit for bit, in its turn, its blocks released then.
// So the memory held is at most the budget plus a few dozen bytes per empty tile, whatever the
// map's size or the order of arrival; the disk held is at most the early tiles' raw bytes.
// Not thread-safe (the writer's owner serializes calls).
#ifndef PDSM_CORE_PDSM_TILE_REORDER_BUFFER_H_
#define PDSM_CORE_PDSM_TILE_REORDER_BUFFER_H_

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>

#include "absl/status/statusor.h"
#include "core/pdsm/pdsm_image.h"
#include "core/util/file_system.h"

namespace pdsm {

// The memory a writer's early tiles may hold before they go to disk: a few rows of tiles of a
// dense map (a 64² tile of 4 vertices a pixel is 160 KiB).
inline constexpr int64_t kTileReorderMemoryBytes = int64_t{64} << 20;

class TileReorderBuffer {
 public:
  // Spilled tiles go to a scratch file in the folder `spill_dir`, created at the first spill.
  // `fs` null means FileSystem::Default(); it must outlive the buffer.
  TileReorderBuffer(std::string spill_dir, int64_t memory_budget_bytes = kTileReorderMemoryBytes,
                    FileSystem* fs = nullptr);
  TileReorderBuffer(const TileReorderBuffer&) = delete;
  TileReorderBuffer& operator=(const TileReorderBuffer&) = delete;
  ~TileReorderBuffer();

  // Keeps `tile` as the tile of index `index`. REQUIRES: no tile of that index held;
  // tile.offsets has width * height + 1 entries. Errors: the scratch file's (RESOURCE_EXHAUSTED
  // for a full disk, …), naming the folder; the tile is not kept then.
  absl::Status Put(int64_t index, PdsmTile tile);

  // Removes and returns the tile of index `index`, or nullopt when none is held. Errors:
  // DATA_LOSS when the scratch file no longer holds what was written (the tile is dropped).
  absl::StatusOr<std::optional<PdsmTile>> Take(int64_t index);

  bool Contains(int64_t index) const { return tiles_.contains(index); }
  size_t size() const { return tiles_.size(); }
  // Heap bytes of the tiles held in memory (their vectors' capacities).
  int64_t memory_bytes() const { return memory_bytes_; }
  // Bytes of the tiles held on disk now.
  int64_t spilled_bytes() const { return spilled_bytes_; }

 private:
  struct Held {
    PdsmTile tile;         // in memory: whole; empty or spilled: its rectangle and samples
    bool empty = false;    // no vertex: offsets all zero, rebuilt on Take
    bool spilled = false;  // offsets and vertices at `offset` in the scratch file
    uint64_t offset = 0;
    uint64_t vertex_count = 0;  // of a spilled tile
  };

  absl::Status Spill(Held* held);
  absl::Status ReadBack(Held* held);

  const std::string spill_dir_;
  const int64_t memory_budget_bytes_;
  FileSystem* const fs_;
  std::map<int64_t, Held> tiles_;
  std::unique_ptr<ScratchFile> scratch_;  // created at the first spill
  uint64_t scratch_end_ = 0;              // spilled tiles are laid end to end
  int64_t memory_bytes_ = 0;
  int64_t spilled_bytes_ = 0;
};

}  // namespace pdsm

#endif  // PDSM_CORE_PDSM_TILE_REORDER_BUFFER_H_
