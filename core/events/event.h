// Events (thesis 3.1): where a PDSM ray enters (+1) or leaves (-1) the shadow of one light
// sample. Events carry no link to each other, so the events of many samples merge by sorting
// on depth and adding counts: integer arithmetic, exact, independent of arrival order.
//
// An emitter-weighted bake (core/events/emitter_weighting.h) must know *which* samples hide a
// point, because each sample's weight changes along the ray: its events are keyed by sample
// (EventKeying::kSampleKeys) and are never summed. Both kinds travel in the same 8 bytes, so
// spills, task results and tile files carry either unchanged; the plan's header says which.
#ifndef PDSM_CORE_EVENTS_EVENT_H_
#define PDSM_CORE_EVENTS_EVENT_H_

#include <cstdint>
#include <span>
#include <vector>

namespace pdsm {

struct Event {
  float z;  // light-space depth, world units
  // kCounts: samples entering (+) or leaving (-) shadow at z. kSampleKeys: +(k + 1) where
  // sample k enters shadow, -(k + 1) where it leaves.
  int32_t count;
  bool operator==(const Event&) const = default;
};

// What the events of a bake hold in `count`.
//   kCounts      summed shadow changes: lists are sorted by depth with distinct depths, and
//                events at one depth add up (zero sums vanish).
//   kSampleKeys  one sample's change each: lists are sorted by (depth, key), one event per
//                sample and depth (a sample that leaves and enters at one depth changes
//                nothing there: both vanish). REQUIRES of every merge: each sample's events are
//                in one input list (a sample belongs to one batch), so merging only
//                interleaves, and its entries and exits alternate.
enum class EventKeying { kCounts, kSampleKeys };

// The key of sample `sample`'s events (kSampleKeys): an event's count is +key or -key.
inline int32_t SampleEventKey(int sample) { return sample + 1; }
// The sample an event of kSampleKeys belongs to.
// (In 64 bits: a hostile count of INT32_MIN has no 32-bit negation.)
inline int SampleOfEvent(const Event& e) {
  const int64_t key = e.count;
  return static_cast<int>((key > 0 ? key : -key) - 1);
}
// How many samples the event puts into (+) or out of (-) shadow.
inline int32_t ShadowChange(const Event& e, EventKeying keying) {
  if (keying == EventKeying::kCounts) return e.count;
  return e.count > 0 ? 1 : -1;
}

// Per-pixel event lists of one tile, each normalized (sorted and combined as its EventKeying
// says: for kCounts, distinct depths and non-zero counts). Pixels are row-major from (x0, y0).
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

// The order of kSampleKeys lists: by depth, then key.
inline bool KeyedBefore(const Event& a, const Event& b) {
  return a.z < b.z || (a.z == b.z && a.count < b.count);
}

// kSampleKeys: appends `group` (events at one depth, sorted by key) to `out` with each sample's
// net change: nothing for a sample that leaves and enters there, one event for one that does
// either once more than the other.
void AppendUncancelledKeys(std::span<const Event> group, std::vector<Event>* out);

// Normalizes in place: kCounts sorts by depth, adds the counts of equal depths and drops zero
// sums; kSampleKeys sorts by (depth, key) and drops a sample's exit and entry at one depth.
void NormalizeEvents(std::vector<Event>* events, EventKeying keying);

// The same for the events from index `first` on (one pixel's, appended after other pixels'
// lists): those before are untouched. REQUIRES: first <= events->size().
void NormalizeEventsFrom(std::vector<Event>* events, size_t first, EventKeying keying);

// Merges normalized lists into one normalized list. The result depends only on the multiset
// of inputs, never on their order.
std::vector<Event> MergeEventLists(std::span<const std::span<const Event>> lists,
                                   EventKeying keying);

// Merges task results for the same tile (any number, any order) into one TileEvents.
// REQUIRES: all parts have the same tile geometry.
TileEvents MergeTileEvents(std::span<const TileEvents> parts, EventKeying keying);

}  // namespace pdsm

#endif  // PDSM_CORE_EVENTS_EVENT_H_
