#include "client/view/pdsm_tile_pool.h"

#include <algorithm>
#include <chrono>
#include <cstring>

#include "absl/strings/str_cat.h"
#include "gl/gl_program.h"

namespace pdsm::view {
namespace {

using Clock = std::chrono::steady_clock;
constexpr uint64_t kUnitBytes = 8;  // one uvec2
// The pool starts this small and doubles as tiles need it, up to its limit: a small map costs
// what it holds, not the budget.
constexpr uint64_t kInitialPoolBytes = uint64_t{4} << 20;

// The page table's entry for a block.
uint32_t PageEntry(int buffer, uint64_t offset) {
  return (static_cast<uint32_t>(buffer) << kPoolOffsetBits) | static_cast<uint32_t>(offset);
}

}  // namespace

PdsmTilePool::PdsmTilePool(const gl::GlFunctions& gl) : gl_(gl) {}

absl::StatusOr<std::unique_ptr<PdsmTilePool>> PdsmTilePool::Create(
    const gl::GlFunctions& gl, std::vector<std::shared_ptr<PdsmTiles>> parts, int64_t budget_bytes,
    int64_t max_buffer_bytes) {
  std::unique_ptr<PdsmTilePool> pool(new PdsmTilePool(gl));
  pool->parts_ = std::move(parts);
  GLint max_block = 0;
  gl.GetIntegerv(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, &max_block);
  uint64_t entries = 0;
  for (const std::shared_ptr<PdsmTiles>& part : pool->parts_) {
    pool->page_bases_.push_back(static_cast<uint32_t>(entries));
    entries += static_cast<uint64_t>(part->tiles_x()) * part->tiles_y();
  }
  if (entries * sizeof(uint32_t) > static_cast<uint64_t>(static_cast<uint32_t>(max_block))) {
    return absl::ResourceExhaustedError(
        absl::StrCat("the PDSM's ", entries,
                     " tiles need a page table larger than one storage "
                     "buffer holds here (",
                     max_block, " bytes)"));
  }
  // One SSBO binding addresses at most GL_MAX_SHADER_STORAGE_BLOCK_SIZE bytes (llvmpipe: 128
  // MiB), and a page entry's offset has kPoolOffsetBits: past that, more buffers.
  pool->buffer_max_units_ = std::min<uint64_t>(static_cast<uint32_t>(max_block) / kUnitBytes,
                                               uint64_t{1} << kPoolOffsetBits);
  if (max_buffer_bytes > 0) {
    pool->buffer_max_units_ = std::min<uint64_t>(
        pool->buffer_max_units_, static_cast<uint64_t>(max_buffer_bytes) / kUnitBytes);
  }
  pool->budget_units_ = std::min<uint64_t>(
      static_cast<uint64_t>(std::max<int64_t>(budget_bytes, kUnitBytes)) / kUnitBytes,
      kMaxPoolBuffers * pool->buffer_max_units_);
  pool->stats_.budget_bytes = pool->budget_units_ * kUnitBytes;

  pool->pages_.assign(entries, kTileNotResident);
  for (size_t i = 0; i < pool->parts_.size(); ++i) {
    const PdsmTiles& part = *pool->parts_[i];
    for (int y = 0; y < part.tiles_y(); ++y) {
      for (int x = 0; x < part.tiles_x(); ++x) {
        if (part.TilePending(x, y)) {
          pool->pages_[pool->page_bases_[i] + static_cast<size_t>(y) * part.tiles_x() + x] =
              kTilePending;
        }
      }
    }
  }
  pool->page_table_ = gl::MakeBuffer(gl);
  gl.BindBuffer(GL_SHADER_STORAGE_BUFFER, pool->page_table_.name());
  gl.BufferData(
      GL_SHADER_STORAGE_BUFFER,
      static_cast<GLsizeiptr>(std::max<size_t>(pool->pages_.size(), 1) * sizeof(uint32_t)),
      pool->pages_.data(), GL_DYNAMIC_DRAW);
  gl.BindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
  pool->stats_.page_table_bytes = pool->pages_.size() * sizeof(uint32_t);

  if (absl::Status s = pool->AddBuffer(); !s.ok()) return s;
  if (absl::Status s = gl::CheckGlError(gl, "making the PDSM tile pool"); !s.ok()) return s;
  return pool;
}

absl::Status PdsmTilePool::AddBuffer() {
  uint64_t given = 0;
  for (const PoolBuffer& b : buffers_) given += b.limit_units;
  PoolBuffer added;
  added.limit_units = std::min(buffer_max_units_, budget_units_ - given);
  const uint64_t initial = std::min(added.limit_units, kInitialPoolBytes / kUnitBytes);
  added.buffer = gl::MakeBuffer(gl_);
  gl_.BindBuffer(GL_SHADER_STORAGE_BUFFER, added.buffer.name());
  gl_.BufferData(GL_SHADER_STORAGE_BUFFER, static_cast<GLsizeiptr>(initial * kUnitBytes), nullptr,
                 GL_DYNAMIC_DRAW);
  gl_.BindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
  added.allocator = RangeAllocator(initial);
  buffers_.push_back(std::move(added));
  UpdateStats();
  return gl::CheckGlError(gl_, "adding a PDSM tile pool buffer");
}

absl::Status PdsmTilePool::GrowBuffer(int i, uint64_t units) {
  PoolBuffer& b = buffers_[i];
  const uint64_t old_units = b.allocator.capacity();
  const uint64_t new_units = std::min(std::max(old_units * 2, old_units + units), b.limit_units);
  if (new_units <= old_units) return absl::OkStatus();
  gl::Buffer grown = gl::MakeBuffer(gl_);
  gl_.BindBuffer(GL_COPY_WRITE_BUFFER, grown.name());
  gl_.BufferData(GL_COPY_WRITE_BUFFER, static_cast<GLsizeiptr>(new_units * kUnitBytes), nullptr,
                 GL_DYNAMIC_DRAW);
  gl_.BindBuffer(GL_COPY_READ_BUFFER, b.buffer.name());
  if (old_units > 0) {
    gl_.CopyBufferSubData(GL_COPY_READ_BUFFER, GL_COPY_WRITE_BUFFER, 0, 0,
                          static_cast<GLsizeiptr>(old_units * kUnitBytes));
  }
  gl_.BindBuffer(GL_COPY_READ_BUFFER, 0);
  gl_.BindBuffer(GL_COPY_WRITE_BUFFER, 0);
  if (absl::Status s = gl::CheckGlError(gl_, "growing the PDSM tile pool"); !s.ok()) return s;
  b.buffer = std::move(grown);
  b.allocator.Grow(new_units);
  UpdateStats();
  return absl::OkStatus();
}

void PdsmTilePool::UpdateStats() {
  stats_.buffers = static_cast<int>(buffers_.size());
  stats_.capacity_bytes = 0;
  stats_.used_bytes = 0;
  for (const PoolBuffer& b : buffers_) {
    stats_.capacity_bytes += b.allocator.capacity() * kUnitBytes;
    stats_.used_bytes += b.allocator.used() * kUnitBytes;
  }
  stats_.resident_tiles = static_cast<int>(resident_.size());
}

bool PdsmTilePool::EvictOne() {
  // The least recently requested tile that the current request does not need.
  auto victim = resident_.end();
  for (auto it = resident_.begin(); it != resident_.end(); ++it) {
    if (it->second.last_request == request_count_) continue;
    if (victim == resident_.end() || it->second.last_request < victim->second.last_request ||
        (it->second.last_request == victim->second.last_request && it->first < victim->first)) {
      victim = it;
    }
  }
  if (victim == resident_.end()) return false;
  buffers_[victim->second.at.buffer].allocator.Free(victim->second.at.offset, victim->second.size);
  pages_[victim->first] = kTileNotResident;
  resident_.erase(victim);
  ++stats_.tiles_evicted;
  return true;
}

void PdsmTilePool::CompactBuffer(int i) {
  PoolBuffer& b = buffers_[i];
  std::unordered_map<uint64_t, size_t> tile_at;  // block offset in this buffer -> tile index
  for (const auto& [index, r] : resident_) {
    if (r.at.buffer == i) tile_at[r.at.offset] = index;
  }
  const std::vector<RangeAllocator::Move> moves = b.allocator.Compact();
  gl::Buffer scratch;
  for (const RangeAllocator::Move& m : moves) {
    const GLsizeiptr bytes = static_cast<GLsizeiptr>(m.size * kUnitBytes);
    const GLintptr from = static_cast<GLintptr>(m.from * kUnitBytes);
    const GLintptr to = static_cast<GLintptr>(m.to * kUnitBytes);
    gl_.BindBuffer(GL_COPY_READ_BUFFER, b.buffer.name());
    if (m.to + m.size <= m.from) {
      gl_.CopyBufferSubData(GL_COPY_READ_BUFFER, GL_COPY_READ_BUFFER, from, to, bytes);
    } else {  // overlapping ranges of one buffer: GL wants a copy in between
      scratch = gl::MakeBuffer(gl_);
      gl_.BindBuffer(GL_COPY_WRITE_BUFFER, scratch.name());
      gl_.BufferData(GL_COPY_WRITE_BUFFER, bytes, nullptr, GL_STREAM_COPY);
      gl_.CopyBufferSubData(GL_COPY_READ_BUFFER, GL_COPY_WRITE_BUFFER, from, 0, bytes);
      gl_.CopyBufferSubData(GL_COPY_WRITE_BUFFER, GL_COPY_READ_BUFFER, 0, to, bytes);
    }
    const size_t index = tile_at.at(m.from);
    resident_[index].at.offset = m.to;
    pages_[index] = PageEntry(i, m.to);
  }
  gl_.BindBuffer(GL_COPY_READ_BUFFER, 0);
  gl_.BindBuffer(GL_COPY_WRITE_BUFFER, 0);
  ++stats_.compactions;
}

std::optional<PdsmTilePool::Placement> PdsmTilePool::Place(uint64_t units) {
  if (units > buffer_max_units_ || units > budget_units_) return std::nullopt;
  for (;;) {
    for (int i = 0; i < static_cast<int>(buffers_.size()); ++i) {
      PoolBuffer& b = buffers_[i];
      if (units > b.limit_units) continue;
      while (true) {
        if (std::optional<uint64_t> offset = b.allocator.Allocate(units)) {
          return Placement{i, *offset};
        }
        if (b.allocator.capacity() >= b.limit_units || !GrowBuffer(i, units).ok()) break;
      }
    }
    uint64_t given = 0;
    for (const PoolBuffer& b : buffers_) given += b.limit_units;
    if (static_cast<int>(buffers_.size()) < kMaxPoolBuffers && given < budget_units_ &&
        std::min(buffer_max_units_, budget_units_ - given) >= units) {
      if (!AddBuffer().ok()) return std::nullopt;
      continue;
    }
    bool compacted = false;
    for (int i = 0; i < static_cast<int>(buffers_.size()) && !compacted; ++i) {
      if (buffers_[i].allocator.free() >= units && buffers_[i].allocator.largest_free() < units) {
        CompactBuffer(i);
        compacted = true;
      }
    }
    if (compacted) continue;
    if (!EvictOne()) return std::nullopt;
  }
}

absl::Status PdsmTilePool::Upload(size_t index, const PdsmTile& tile, Placement at,
                                  uint64_t units) {
  const size_t pixels = static_cast<size_t>(tile.width) * tile.height;
  std::vector<uint32_t> block(2 * units);
  for (size_t p = 0; p < pixels; ++p) {
    block[2 * p] = static_cast<uint32_t>(pixels + tile.offsets[p]);
    block[2 * p + 1] = static_cast<uint32_t>(tile.offsets[p + 1] - tile.offsets[p]);
  }
  static_assert(sizeof(Vertex) == 2 * sizeof(float), "Vertex is (z, A) float32");
  std::memcpy(&block[2 * pixels], tile.vertices.data(), tile.vertices.size() * sizeof(Vertex));
  gl_.BindBuffer(GL_SHADER_STORAGE_BUFFER, buffers_[at.buffer].buffer.name());
  gl_.BufferSubData(GL_SHADER_STORAGE_BUFFER, static_cast<GLintptr>(at.offset * kUnitBytes),
                    static_cast<GLsizeiptr>(units * kUnitBytes), block.data());
  gl_.BindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
  pages_[index] = PageEntry(at.buffer, at.offset);
  ++stats_.tiles_uploaded;
  return gl::CheckGlError(gl_, "uploading a PDSM tile");
}

absl::Status PdsmTilePool::Request(std::vector<TileRequest> requests) {
  const auto start = Clock::now();
  ++request_count_;
  std::sort(requests.begin(), requests.end(), [](const TileRequest& a, const TileRequest& b) {
    if (a.pixels != b.pixels) return a.pixels > b.pixels;
    if (a.part != b.part) return a.part < b.part;
    return a.tile_y != b.tile_y ? a.tile_y < b.tile_y : a.tile_x < b.tile_x;
  });
  const auto index_of = [this](const TileRequest& r) {
    return page_bases_[r.part] + static_cast<size_t>(r.tile_y) * parts_[r.part]->tiles_x() +
           r.tile_x;
  };
  // First mark every requested resident tile as in use, so that none of them is evicted for
  // another.
  for (const TileRequest& r : requests) {
    auto it = resident_.find(index_of(r));
    if (it != resident_.end()) it->second.last_request = request_count_;
  }
  stats_.requested_tiles = static_cast<int>(requests.size());
  stats_.missing_tiles = 0;
  stats_.missing_pixels = 0;
  bool changed = false;
  absl::Status status;
  for (const TileRequest& r : requests) {
    const size_t index = index_of(r);
    if (pages_[index] != kTileNotResident) continue;  // resident, empty or pending
    absl::StatusOr<std::shared_ptr<const PdsmTile>> tile = parts_[r.part]->Tile(r.tile_x, r.tile_y);
    if (!tile.ok()) {
      status = tile.status();
      break;
    }
    changed = true;
    if (*tile == nullptr) {
      pages_[index] = kTilePending;
      continue;
    }
    if ((*tile)->vertices.empty()) {
      pages_[index] = kTileEmpty;
      ++stats_.empty_tiles;
      continue;
    }
    const uint64_t units =
        static_cast<uint64_t>((*tile)->width) * (*tile)->height + (*tile)->vertices.size();
    const std::optional<Placement> at = Place(units);
    if (!at) {
      ++stats_.missing_tiles;
      stats_.missing_pixels += r.pixels;
      continue;
    }
    if (status = Upload(index, **tile, *at, units); !status.ok()) break;
    resident_[index] = Resident{*at, units, request_count_};
  }
  if (changed) {
    gl_.BindBuffer(GL_SHADER_STORAGE_BUFFER, page_table_.name());
    gl_.BufferSubData(GL_SHADER_STORAGE_BUFFER, 0,
                      static_cast<GLsizeiptr>(pages_.size() * sizeof(uint32_t)), pages_.data());
    gl_.BindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
  }
  UpdateStats();
  stats_.upload_seconds += std::chrono::duration<double>(Clock::now() - start).count();
  if (!status.ok()) return status;
  return gl::CheckGlError(gl_, "updating the PDSM page table");
}

}  // namespace pdsm::view
