// Events (thesis 3.1): where a PDSM ray enters (+1) or leaves (-1) the shadow of one light
// sample. Events carry no link to each other, so the events of many samples merge by sorting
// on depth and adding counts: integer arithmetic, exact, independent of arrival order.
#ifndef PDSM_CORE_EVENTS_EVENT_H_
#define PDSM_CORE_EVENTS_EVENT_H_

#include <cstdint>
#include <span>
#include <vector>

namespace pdsm {

struct Event {
  float z;        // light-space depth, world units
  int32_t count;  // samples entering (+) or leaving (-) shadow at z
  bool operator==(const Event&) const = default;
};

// Per-pixel event lists of one tile, each sorted by depth with distinct depths and non-zero
// counts ("normalized"). Pixels are row-major from (x0, y0).
struct TileEvents {
  int tile_index = 0;
  int x0 = 0, y0 = 0, width = 0, height = 0;
  std::vector<uint64_t> offsets;  // width * height + 1
  std::vector<Event> events;

  std::span<const Event> Pixel(size_t p) const {
    return {events.data() + offsets[p], events.data() + offsets[p + 1]};
  }
  size_t PixelCount() const { return static_cast<size_t>(width) * height; }
};

// The tile's index and rectangle, without lists (offsets and events empty).
TileEvents TileShape(const TileEvents& events);

// Sorts by depth, adds the counts of equal depths and drops zero sums, in place.
void NormalizeEvents(std::vector<Event>* events);

// The same for the events from index `first` on (one pixel's, appended after other pixels'
// lists): those before are untouched. REQUIRES: first <= events->size().
void NormalizeEventsFrom(std::vector<Event>* events, size_t first);

// Merges normalized lists into one normalized list. The result depends only on the multiset
// of inputs, never on their order.
std::vector<Event> MergeEventLists(std::span<const std::span<const Event>> lists);

// Merges task results for the same tile (any number, any order) into one TileEvents.
// REQUIRES: all parts have the same tile geometry.
TileEvents MergeTileEvents(std::span<const TileEvents> parts);

}  // namespace pdsm

#endif  // PDSM_CORE_EVENTS_EVENT_H_
