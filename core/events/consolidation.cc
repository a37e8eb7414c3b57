#include "core/events/consolidation.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace pdsm {

std::vector<Event> ConsolidateEvents(std::span<const Event> events, EventKeying keying) {
  std::vector<Event> out;
  out.reserve(events.size());
  std::vector<Event> run;
  for (size_t i = 0; i < events.size();) {
    const float z = events[i].z;
    const double limit = z + kConsolidationRelativeDepth * std::abs(static_cast<double>(z));
    if (keying == EventKeying::kSampleKeys) {
      run.clear();
      for (; i < events.size() && events[i].z <= limit; ++i) run.push_back({z, events[i].count});
      if (run.size() > 1) std::sort(run.begin(), run.end(), KeyedBefore);
      AppendUncancelledKeys(run, &out);
      continue;
    }
    int64_t sum = 0;
    for (; i < events.size() && events[i].z <= limit; ++i) sum += events[i].count;
    if (sum != 0) out.push_back(Event{z, static_cast<int32_t>(sum)});
  }
  return out;
}

std::vector<Vertex> FunctionFromEvents(std::span<const Event> events, int total_samples) {
  std::vector<Vertex> function;
  function.reserve(2 * events.size());
  int64_t hidden = 0;
  for (const Event& e : events) {
    const float before = static_cast<float>(static_cast<double>(hidden) / total_samples);
    hidden += e.count;
    const float after = static_cast<float>(static_cast<double>(hidden) / total_samples);
    function.push_back(Vertex{e.z, before});
    function.push_back(Vertex{e.z, after});
  }
  return function;
}

}  // namespace pdsm
