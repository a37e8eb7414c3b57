#include "core/events/event.h"

#include <algorithm>
#include <cassert>
#include <utility>

namespace pdsm {
namespace {

// Appends the merge of normalized lists `a` and `b` to `out`: one linear pass, equal depths
// summed, zero sums dropped, so the result is normalized (and the same in either order).
// kSampleKeys lists hold different samples (the merge's REQUIRES), so nothing combines: the
// pass only interleaves them by (depth, key).
template <EventKeying kKeying>
void AppendMergeOfTwo(std::span<const Event> a, std::span<const Event> b, std::vector<Event>* out) {
  size_t i = 0, j = 0;
  if constexpr (kKeying == EventKeying::kSampleKeys) {
    while (i < a.size() && j < b.size()) {
      out->push_back(KeyedBefore(b[j], a[i]) ? b[j++] : a[i++]);
    }
    out->insert(out->end(), a.begin() + i, a.end());
    out->insert(out->end(), b.begin() + j, b.end());
    return;
  }
  while (i < a.size() && j < b.size()) {
    if (a[i].z < b[j].z) {
      out->push_back(a[i++]);
    } else if (b[j].z < a[i].z) {
      out->push_back(b[j++]);
    } else {
      const int64_t sum = int64_t{a[i].count} + b[j].count;
      if (sum != 0) out->push_back(Event{a[i].z, static_cast<int32_t>(sum)});
      ++i, ++j;
    }
  }
  out->insert(out->end(), a.begin() + i, a.end());
  out->insert(out->end(), b.begin() + j, b.end());
}

// Appends the merge of normalized `lists` to `out`: pairwise rounds of linear merges
// (O(n log k) for k lists of n events in all, where sorting the concatenation was O(n log n)).
template <EventKeying kKeying>
void AppendMerge(std::span<const std::span<const Event>> lists, std::vector<Event>* out) {
  // One or two lists with events (the usual case: a running list and a batch) take no
  // allocation.
  std::span<const Event> first, second;
  int non_empty = 0;
  for (const auto& list : lists) {
    if (list.empty()) continue;
    (non_empty == 0 ? first : second) = list;
    if (++non_empty > 2) break;
  }
  if (non_empty == 0) return;
  if (non_empty == 1) {
    out->insert(out->end(), first.begin(), first.end());
    return;
  }
  if (non_empty == 2) return AppendMergeOfTwo<kKeying>(first, second, out);
  std::vector<std::span<const Event>> round;
  for (const auto& list : lists) {
    if (!list.empty()) round.push_back(list);
  }
  // Each round halves the lists; its merged lists live in one buffer per round, so the spans
  // of a round stay valid while the next round reads them.
  std::vector<Event> buffers[2];
  int current = 0;
  while (round.size() > 2) {
    std::vector<Event>& buffer = buffers[current];
    buffer.clear();
    size_t total = 0;
    for (const auto& list : round) total += list.size();
    buffer.reserve(total);
    std::vector<std::pair<size_t, size_t>> pieces;  // [begin, end) in buffer
    for (size_t k = 0; k + 1 < round.size(); k += 2) {
      const size_t begin = buffer.size();
      AppendMergeOfTwo<kKeying>(round[k], round[k + 1], &buffer);
      pieces.emplace_back(begin, buffer.size());
    }
    if (round.size() % 2 == 1) {
      const size_t begin = buffer.size();
      buffer.insert(buffer.end(), round.back().begin(), round.back().end());
      pieces.emplace_back(begin, buffer.size());
    }
    round.clear();
    for (const auto& [begin, end] : pieces) {
      round.emplace_back(buffer.data() + begin, end - begin);
    }
    current = 1 - current;
  }
  AppendMergeOfTwo<kKeying>(round[0], round[1], out);
}

void AppendMerge(std::span<const std::span<const Event>> lists, EventKeying keying,
                 std::vector<Event>* out) {
  if (keying == EventKeying::kSampleKeys) return AppendMerge<EventKeying::kSampleKeys>(lists, out);
  AppendMerge<EventKeying::kCounts>(lists, out);
}

// kSampleKeys normalization: sorted by (depth, key); at each depth a sample that both leaves
// and enters (two pieces of a ray meeting there) changes nothing and is dropped.
void NormalizeKeyedFrom(std::vector<Event>* events, size_t first) {
  std::sort(events->begin() + static_cast<ptrdiff_t>(first), events->end(),
            [](const Event& a, const Event& b) { return KeyedBefore(a, b); });
  size_t out = first;
  std::vector<Event> kept;
  for (size_t i = first; i < events->size();) {
    const float z = (*events)[i].z;
    size_t end = i + 1;
    while (end < events->size() && (*events)[end].z == z) ++end;
    if (end == i + 1) {  // the usual case: one sample changes at this depth
      (*events)[out++] = (*events)[i];
    } else {
      kept.clear();
      AppendUncancelledKeys({events->data() + i, end - i}, &kept);
      for (const Event& e : kept) (*events)[out++] = e;
    }
    i = end;
  }
  events->resize(out);
}

}  // namespace

TileEvents TileShape(const TileEvents& events) {
  return TileEvents{.tile_index = events.tile_index,
                    .x0 = events.x0,
                    .y0 = events.y0,
                    .width = events.width,
                    .height = events.height,
                    .offsets = {},
                    .events = {}};
}

void AppendUncancelledKeys(std::span<const Event> group, std::vector<Event>* out) {
  // Sorted by key, so equal keys are adjacent: a sample's net change is its entries less its
  // exits (each run of one key against the run of its opposite).
  for (size_t i = 0; i < group.size();) {
    size_t end = i + 1;
    while (end < group.size() && group[end].count == group[i].count) ++end;
    const Event opposite{group[i].z, -group[i].count};
    const auto [lo, hi] = std::equal_range(group.begin(), group.end(), opposite, KeyedBefore);
    for (ptrdiff_t net = static_cast<ptrdiff_t>(end - i) - (hi - lo); net > 0; --net) {
      out->push_back(group[i]);
    }
    i = end;
  }
}

void NormalizeEvents(std::vector<Event>* events, EventKeying keying) {
  NormalizeEventsFrom(events, 0, keying);
}

void NormalizeEventsFrom(std::vector<Event>* events, size_t first, EventKeying keying) {
  if (keying == EventKeying::kSampleKeys) return NormalizeKeyedFrom(events, first);
  // A lambda, not a function pointer: std::sort inlines it (a pointer comparator cost 10 % of
  // a bake's CPU in calls). Any order of equal depths gives the same sums below.
  std::sort(events->begin() + static_cast<ptrdiff_t>(first), events->end(),
            [](const Event& a, const Event& b) { return a.z < b.z; });
  size_t out = first;
  for (size_t i = first; i < events->size();) {
    const float z = (*events)[i].z;
    int64_t sum = 0;
    for (; i < events->size() && (*events)[i].z == z; ++i) sum += (*events)[i].count;
    if (sum != 0) (*events)[out++] = Event{z, static_cast<int32_t>(sum)};
  }
  events->resize(out);
}

std::vector<Event> MergeEventLists(std::span<const std::span<const Event>> lists,
                                   EventKeying keying) {
  std::vector<Event> merged;
  AppendMerge(lists, keying, &merged);
  return merged;
}

TileEvents MergeTileEvents(std::span<const TileEvents> parts, EventKeying keying) {
  if (parts.empty()) return TileEvents{};
  const TileEvents& first = parts.front();
  TileEvents merged = TileShape(first);
  const size_t pixels = first.PixelCount();
  size_t total = 0, with_events = 0;
  const TileEvents* only = nullptr;
  for (const TileEvents& part : parts) {
    total += part.events.size();
    if (!part.events.empty()) ++with_events, only = &part;
  }
  if (with_events <= 1) {  // nothing to merge: the one part with events, or none
    merged.offsets = only ? only->offsets : std::vector<uint64_t>(pixels + 1, 0);
    if (only) merged.events = only->events;
    return merged;
  }
  merged.offsets.assign(pixels + 1, 0);
  merged.events.reserve(total);  // an upper bound: equal depths only shrink it
  std::vector<std::span<const Event>> lists(parts.size());
  for (size_t p = 0; p < pixels; ++p) {
    for (size_t k = 0; k < parts.size(); ++k) {
      assert(parts[k].PixelCount() == pixels);
      lists[k] = parts[k].Pixel(p);
    }
    AppendMerge(lists, keying, &merged.events);
    merged.offsets[p + 1] = merged.events.size();
  }
  merged.events.shrink_to_fit();
  return merged;
}

}  // namespace pdsm
