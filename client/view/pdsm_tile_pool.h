// The PDSM on the GPU as a virtual texture (issue #12): a page table with one entry per PDSM
// tile of every part shown (one light, or every light of a file and a sphere's faces), and
// pool buffers holding the tiles that are resident, under a GPU memory budget
// (`pdsm-view --gpu-budget-mib`). The frame renderer asks for the tiles a frame reads; they
// are read from the PdsmTiles source and uploaded, evicting least recently used tiles no
// longer needed when the pool is full. A map of any size is drawn with the GPU memory of what
// is on screen, not of the map.
//
// Layout (read by shaders/view/shade.frag):
//   page table  SSBO of uint: each part's tiles_x x tiles_y entries, row-major from t_min,
//               from page_base(part): the tile's block as (pool buffer << kPoolOffsetBits) |
//               offset in that buffer (8-byte units), or kTileEmpty / kTilePending /
//               kTileNotResident.
//   pool        up to kMaxPoolBuffers SSBOs of uvec2: one binding addresses at most
//               GL_MAX_SHADER_STORAGE_BLOCK_SIZE (llvmpipe: 128 MiB), more buffers let the
//               budget pass that. A tile's block: width * height entries (offset of the
//               pixel's first vertex from the block start, vertex count), row-major, then its
//               vertices (z, A) as float32 bit patterns. The thesis' two levels (4.2.4) per
//               tile: no fixed maximum depth per pixel.
// The vertices are the file's float32, copied bit for bit. Offsets are relative to the block,
// so a block moves (compaction) by copying it and changing its page table entry.
//
// Thread safety: none; the GL context must be current on the calling thread.
#ifndef PDSM_CLIENT_VIEW_PDSM_TILE_POOL_H_
#define PDSM_CLIENT_VIEW_PDSM_TILE_POOL_H_

#include <cstdint>
#include <memory>
#include <optional>
#include <unordered_map>
#include <vector>

#include "absl/status/statusor.h"
#include "client/view/pdsm_tiles.h"
#include "client/view/range_allocator.h"
#include "gl/gl_functions.h"
#include "gl/gl_objects.h"

namespace pdsm::view {

// Page table entries that are not a block offset.
inline constexpr uint32_t kTileNotResident = 0xFFFFFFFDu;  // over the budget, or not asked yet
inline constexpr uint32_t kTileEmpty = 0xFFFFFFFEu;        // no vertex in the tile: A = 0
inline constexpr uint32_t kTilePending = 0xFFFFFFFFu;      // not baked yet (a running job)
// A resident tile's entry: its pool buffer in the bits above kPoolOffsetBits, its offset in
// 8-byte units below (so a buffer holds at most 2 GiB).
inline constexpr int kPoolOffsetBits = 28;
inline constexpr int kMaxPoolBuffers = 4;

// `pdsm-view --gpu-budget-mib` unless set.
inline constexpr int64_t kDefaultGpuBudgetBytes = int64_t{256} << 20;

struct TileRequest {
  int part = 0;  // index into the pool's parts
  int tile_x = 0, tile_y = 0;
  int64_t pixels = 0;  // screen pixels that read the tile: the most read are made resident first
};

struct TilePoolStats {
  uint64_t budget_bytes = 0;    // the pool's limit: the budget, or what kMaxPoolBuffers hold
  uint64_t capacity_bytes = 0;  // allocated now (grows up to the limit as tiles need it)
  int buffers = 0;              // pool buffers in use
  uint64_t used_bytes = 0;      // resident blocks
  uint64_t page_table_bytes = 0;
  int resident_tiles = 0;
  int empty_tiles = 0;         // known to hold no vertex (no pool space)
  int requested_tiles = 0;     // by the last request
  int missing_tiles = 0;       // of those, not resident (over the budget)
  int64_t missing_pixels = 0;  // the pixels that read them
  int64_t tiles_uploaded = 0;  // since creation
  int64_t tiles_evicted = 0;
  int compactions = 0;
  double upload_seconds = 0;  // reading, packing and uploading tiles, since creation
};

class PdsmTilePool {
 public:
  // REQUIRES: a current GL 4.3+ context made by the driver `gl` was loaded from; `gl` outlives
  // the pool; `parts` not empty. `max_buffer_bytes` (> 0) caps one pool buffer below what the
  // GL allows (tests of several buffers). RESOURCE_EXHAUSTED when the page table exceeds one
  // storage buffer; INTERNAL when GL fails.
  static absl::StatusOr<std::unique_ptr<PdsmTilePool>> Create(
      const gl::GlFunctions& gl, std::vector<std::shared_ptr<PdsmTiles>> parts,
      int64_t budget_bytes, int64_t max_buffer_bytes = 0);
  PdsmTilePool(const PdsmTilePool&) = delete;
  PdsmTilePool& operator=(const PdsmTilePool&) = delete;

  // Makes the requested tiles resident, the most read first (ties: row-major order), as far as
  // the budget goes: tiles not requested are evicted least recently requested first, and the
  // pool is compacted when its free space is fragmented. Requested tiles that do not fit stay
  // kTileNotResident (counted in stats()). REQUIRES: each request names a tile of one of the
  // parts. Errors: reading a tile (naming the file), GL.
  absl::Status Request(std::vector<TileRequest> requests);

  GLuint page_table() const { return page_table_.name(); }
  // Where part `part`'s entries start in the page table.
  uint32_t page_base(int part) const { return page_bases_.at(part); }
  // Pool buffer `i`, or 0 past the buffers made so far (a binding the shader never reads).
  GLuint pool(int i) const {
    return i < static_cast<int>(buffers_.size()) ? buffers_[i].buffer.name() : 0;
  }
  uint64_t pool_capacity_bytes(int i) const { return buffers_.at(i).allocator.capacity() * 8; }
  int tile_size(int part = 0) const { return parts_.at(part)->header().tile_size; }
  const TilePoolStats& stats() const { return stats_; }

 private:
  struct Placement {
    int buffer = 0;
    uint64_t offset = 0;  // 8-byte units
  };
  struct Resident {
    Placement at;
    uint64_t size = 0;  // 8-byte units
    uint64_t last_request = 0;
  };
  struct PoolBuffer {
    gl::Buffer buffer;
    RangeAllocator allocator;
    uint64_t limit_units = 0;
  };
  explicit PdsmTilePool(const gl::GlFunctions& gl);
  // A free block of `units`: in a buffer as it is, grown, or a new one; then compacting a
  // buffer whose free space is fragmented; then evicting. nullopt if none.
  std::optional<Placement> Place(uint64_t units);
  bool EvictOne();
  absl::Status GrowBuffer(int i, uint64_t units);
  absl::Status AddBuffer();
  void CompactBuffer(int i);
  absl::Status Upload(size_t index, const PdsmTile& tile, Placement at, uint64_t units);
  void UpdateStats();

  const gl::GlFunctions& gl_;
  std::vector<std::shared_ptr<PdsmTiles>> parts_;
  std::vector<uint32_t> page_bases_;  // per part
  gl::Buffer page_table_;
  std::vector<PoolBuffer> buffers_;
  uint64_t budget_units_ = 0;                      // over every buffer
  uint64_t buffer_max_units_ = 0;                  // what one buffer may hold
  std::vector<uint32_t> pages_;                    // the page table
  std::unordered_map<size_t, Resident> resident_;  // by page table index
  uint64_t request_count_ = 0;
  TilePoolStats stats_;
};

}  // namespace pdsm::view

#endif  // PDSM_CLIENT_VIEW_PDSM_TILE_POOL_H_
