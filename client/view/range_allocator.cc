#include "client/view/range_allocator.h"

#include <algorithm>

namespace pdsm::view {

RangeAllocator::RangeAllocator(uint64_t capacity) : capacity_(capacity) {
  if (capacity > 0) free_[0] = capacity;
}

uint64_t RangeAllocator::largest_free() const {
  uint64_t largest = 0;
  for (const auto& [offset, size] : free_) largest = std::max(largest, size);
  return largest;
}

std::optional<uint64_t> RangeAllocator::Allocate(uint64_t size) {
  if (size == 0) return std::nullopt;
  for (auto it = free_.begin(); it != free_.end(); ++it) {
    if (it->second < size) continue;
    const uint64_t offset = it->first, left = it->second - size;
    free_.erase(it);
    if (left > 0) free_[offset + size] = left;
    held_[offset] = size;
    used_ += size;
    return offset;
  }
  return std::nullopt;
}

void RangeAllocator::Free(uint64_t offset, uint64_t size) {
  held_.erase(offset);
  used_ -= size;
  auto next = free_.lower_bound(offset);
  if (next != free_.end() && next->first == offset + size) {  // merge with the range after
    size += next->second;
    next = free_.erase(next);
  }
  if (next != free_.begin()) {
    auto previous = std::prev(next);
    if (previous->first + previous->second == offset) {  // and with the range before
      previous->second += size;
      return;
    }
  }
  free_[offset] = size;
}

void RangeAllocator::Grow(uint64_t new_capacity) {
  if (new_capacity <= capacity_) return;
  const uint64_t added = new_capacity - capacity_;
  const uint64_t old_end = capacity_;
  capacity_ = new_capacity;
  if (!free_.empty()) {
    auto last = std::prev(free_.end());
    if (last->first + last->second == old_end) {
      last->second += added;
      return;
    }
  }
  free_[old_end] = added;
}

std::vector<RangeAllocator::Move> RangeAllocator::Compact() {
  std::vector<Move> moves;
  std::map<uint64_t, uint64_t> held;
  uint64_t next = 0;
  for (const auto& [offset, size] : held_) {
    if (offset != next) moves.push_back({offset, next, size});
    held[next] = size;
    next += size;
  }
  held_ = std::move(held);
  free_.clear();
  if (next < capacity_) free_[next] = capacity_ - next;
  return moves;
}

}  // namespace pdsm::view
