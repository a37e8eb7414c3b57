#include "core/pdsm/tile_reorder_buffer.h"

#include <utility>
#include <vector>

#include "absl/strings/str_cat.h"

namespace pdsm {
namespace {

int64_t HeapBytes(const PdsmTile& tile) {
  return static_cast<int64_t>(tile.offsets.capacity() * sizeof(uint64_t) +
                              tile.vertices.capacity() * sizeof(Vertex));
}

size_t OffsetCount(const PdsmTile& tile) {
  return static_cast<size_t>(tile.width) * tile.height + 1;
}

}  // namespace

TileReorderBuffer::TileReorderBuffer(std::string spill_dir, int64_t memory_budget_bytes,
                                     FileSystem* fs)
    : spill_dir_(std::move(spill_dir)),
      memory_budget_bytes_(memory_budget_bytes),
      fs_(fs != nullptr ? fs : FileSystem::Default()) {}

TileReorderBuffer::~TileReorderBuffer() = default;

absl::Status TileReorderBuffer::Put(int64_t index, PdsmTile tile) {
  Held held;
  if (tile.vertices.empty()) {
    held.empty = true;
    std::vector<uint64_t>().swap(tile.offsets);  // all zero: rebuilt on Take
  }
  held.tile = std::move(tile);
  const int64_t bytes = HeapBytes(held.tile);
  if (!held.empty && memory_bytes_ + bytes > memory_budget_bytes_) {
    if (absl::Status s = Spill(&held); !s.ok()) return s;
  } else {
    memory_bytes_ += bytes;
  }
  tiles_.emplace(index, std::move(held));
  return absl::OkStatus();
}

absl::StatusOr<std::optional<PdsmTile>> TileReorderBuffer::Take(int64_t index) {
  auto it = tiles_.find(index);
  if (it == tiles_.end()) return std::optional<PdsmTile>();
  Held held = std::move(it->second);
  tiles_.erase(it);
  if (held.empty) {
    held.tile.offsets.assign(OffsetCount(held.tile), 0);
  } else if (held.spilled) {
    if (absl::Status s = ReadBack(&held); !s.ok()) return s;
  } else {
    memory_bytes_ -= HeapBytes(held.tile);
  }
  return std::optional<PdsmTile>(std::move(held.tile));
}

absl::Status TileReorderBuffer::Spill(Held* held) {
  if (!scratch_) {
    absl::StatusOr<std::unique_ptr<ScratchFile>> file = fs_->NewScratchFile(spill_dir_);
    if (!file.ok()) return file.status();
    scratch_ = *std::move(file);
  }
  PdsmTile& tile = held->tile;
  const absl::string_view offsets(reinterpret_cast<const char*>(tile.offsets.data()),
                                  tile.offsets.size() * sizeof(uint64_t));
  const absl::string_view vertices(reinterpret_cast<const char*>(tile.vertices.data()),
                                   tile.vertices.size() * sizeof(Vertex));
  if (absl::Status s = scratch_->WriteAt(scratch_end_, offsets); !s.ok()) return s;
  if (absl::Status s = scratch_->WriteAt(scratch_end_ + offsets.size(), vertices); !s.ok()) {
    return s;
  }
  held->spilled = true;
  held->offset = scratch_end_;
  held->vertex_count = tile.vertices.size();
  scratch_end_ += offsets.size() + vertices.size();
  spilled_bytes_ += static_cast<int64_t>(offsets.size() + vertices.size());
  std::vector<uint64_t>().swap(tile.offsets);
  std::vector<Vertex>().swap(tile.vertices);
  return absl::OkStatus();
}

absl::Status TileReorderBuffer::ReadBack(Held* held) {
  PdsmTile& tile = held->tile;
  tile.offsets.resize(OffsetCount(tile));
  tile.vertices.resize(held->vertex_count);
  const size_t offset_bytes = tile.offsets.size() * sizeof(uint64_t);
  const size_t vertex_bytes = tile.vertices.size() * sizeof(Vertex);
  absl::Status s =
      scratch_->ReadAt(held->offset, offset_bytes, reinterpret_cast<char*>(tile.offsets.data()));
  if (s.ok()) {
    s = scratch_->ReadAt(held->offset + offset_bytes, vertex_bytes,
                         reinterpret_cast<char*>(tile.vertices.data()));
  }
  scratch_->Release(held->offset, offset_bytes + vertex_bytes);
  spilled_bytes_ -= static_cast<int64_t>(offset_bytes + vertex_bytes);
  if (!s.ok()) return s;
  if (tile.offsets.front() != 0 || tile.offsets.back() != held->vertex_count) {
    return absl::DataLossError(absl::StrCat(scratch_->label(), ": a spilled tile at (", tile.x0,
                                            ", ", tile.y0, ") came back with offsets ",
                                            tile.offsets.front(), "..", tile.offsets.back(),
                                            " for ", held->vertex_count, " vertices"));
  }
  return absl::OkStatus();
}

}  // namespace pdsm
