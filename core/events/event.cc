#include "core/events/event.h"

#include <algorithm>
#include <cassert>

namespace pdsm {

void NormalizeEvents(std::vector<Event>* events) {
  // A lambda, not a function pointer: std::sort inlines it (a pointer comparator cost 10 % of
  // a bake's CPU in calls). Any order of equal depths gives the same sums below.
  std::sort(events->begin(), events->end(),
            [](const Event& a, const Event& b) { return a.z < b.z; });
  size_t out = 0;
  for (size_t i = 0; i < events->size();) {
    const float z = (*events)[i].z;
    int64_t sum = 0;
    for (; i < events->size() && (*events)[i].z == z; ++i) sum += (*events)[i].count;
    if (sum != 0) (*events)[out++] = Event{z, static_cast<int32_t>(sum)};
  }
  events->resize(out);
}

std::vector<Event> MergeEventLists(std::span<const std::span<const Event>> lists) {
  size_t total = 0;
  for (const auto& list : lists) total += list.size();
  std::vector<Event> merged;
  merged.reserve(total);
  for (const auto& list : lists) merged.insert(merged.end(), list.begin(), list.end());
  // Sorting by depth alone is enough: equal depths are summed, and integer sums do not
  // depend on the order of their terms.
  NormalizeEvents(&merged);
  return merged;
}

TileEvents MergeTileEvents(std::span<const TileEvents> parts) {
  TileEvents merged;
  if (parts.empty()) return merged;
  const TileEvents& first = parts.front();
  merged.tile_index = first.tile_index;
  merged.x0 = first.x0;
  merged.y0 = first.y0;
  merged.width = first.width;
  merged.height = first.height;
  const size_t pixels = first.PixelCount();
  merged.offsets.assign(pixels + 1, 0);
  std::vector<std::span<const Event>> lists(parts.size());
  for (size_t p = 0; p < pixels; ++p) {
    for (size_t k = 0; k < parts.size(); ++k) {
      assert(parts[k].PixelCount() == pixels);
      lists[k] = parts[k].Pixel(p);
    }
    const std::vector<Event> pixel = MergeEventLists(lists);
    merged.events.insert(merged.events.end(), pixel.begin(), pixel.end());
    merged.offsets[p + 1] = merged.events.size();
  }
  return merged;
}

}  // namespace pdsm
