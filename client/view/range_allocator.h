// First-fit allocation of ranges [offset, offset + size) in a pool of `capacity` units (the
// viewer's GPU tile pool: units of 8 bytes). Freed ranges merge with their free neighbours, so
// free space fragments only between ranges still held; Compact moves every held range down to
// close the gaps, in address order, and reports the moves for the caller to copy the data.
// Not thread-safe.
#ifndef PDSM_CLIENT_VIEW_RANGE_ALLOCATOR_H_
#define PDSM_CLIENT_VIEW_RANGE_ALLOCATOR_H_

#include <cstdint>
#include <map>
#include <optional>
#include <vector>

namespace pdsm::view {

class RangeAllocator {
 public:
  explicit RangeAllocator(uint64_t capacity = 0);

  uint64_t capacity() const { return capacity_; }
  uint64_t used() const { return used_; }
  uint64_t free() const { return capacity_ - used_; }
  // The largest range Allocate could return now.
  uint64_t largest_free() const;

  // The lowest free range of `size` units (size > 0), or nullopt when no free range is long
  // enough (free() may still be larger: fragmentation).
  std::optional<uint64_t> Allocate(uint64_t size);
  // REQUIRES: [offset, offset + size) was returned by Allocate and not freed since.
  void Free(uint64_t offset, uint64_t size);

  // More capacity at the end (the pool grew).
  void Grow(uint64_t new_capacity);

  struct Move {
    uint64_t from = 0, to = 0, size = 0;  // to < from
  };
  // Moves every held range as low as it goes, keeping their order; returns the moves in the
  // order they must be done (ascending addresses: a move never overwrites a range not yet
  // moved, but its source and destination may overlap).
  std::vector<Move> Compact();

 private:
  uint64_t capacity_ = 0;
  uint64_t used_ = 0;
  std::map<uint64_t, uint64_t> free_;  // offset -> size, disjoint, never adjacent
  std::map<uint64_t, uint64_t> held_;  // offset -> size
};

}  // namespace pdsm::view

#endif  // PDSM_CLIENT_VIEW_RANGE_ALLOCATOR_H_
