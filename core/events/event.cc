#include "core/events/event.h"

#include <algorithm>
#include <cassert>
#include <utility>

namespace pdsm {
namespace {

// Appends the merge of normalized lists `a` and `b` to `out`: one linear pass, equal depths
// summed, zero sums dropped, so the result is normalized (and the same in either order).
void AppendMergeOfTwo(std::span<const Event> a, std::span<const Event> b, std::vector<Event>* out) {
  size_t i = 0, j = 0;
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
  if (non_empty == 2) return AppendMergeOfTwo(first, second, out);
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
      AppendMergeOfTwo(round[k], round[k + 1], &buffer);
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
  AppendMergeOfTwo(round[0], round[1], out);
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

void NormalizeEvents(std::vector<Event>* events) { NormalizeEventsFrom(events, 0); }

void NormalizeEventsFrom(std::vector<Event>* events, size_t first) {
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

std::vector<Event> MergeEventLists(std::span<const std::span<const Event>> lists) {
  std::vector<Event> merged;
  AppendMerge(lists, &merged);
  return merged;
}

TileEvents MergeTileEvents(std::span<const TileEvents> parts) {
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
    AppendMerge(lists, &merged.events);
    merged.offsets[p + 1] = merged.events.size();
  }
  merged.events.shrink_to_fit();
  return merged;
}

}  // namespace pdsm
