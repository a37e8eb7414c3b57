// Consolidation (thesis 3.1): after the merge, events closer in depth than the shadow maps can
// resolve are one event. Deterministic: groups are formed greedily from the nearest event.
#ifndef PDSM_CORE_EVENTS_CONSOLIDATION_H_
#define PDSM_CORE_EVENTS_CONSOLIDATION_H_

#include <span>
#include <vector>

#include "core/events/event.h"
#include "core/pdsm/attenuation_function.h"

namespace pdsm {

// Relative depth resolution of the shadow maps: they store float32 light-space depths
// (24-bit mantissa); 2^-19 is 16 ulps, below which two depths cannot be told apart after the
// bias and the rasterizer's own rounding.
inline constexpr double kConsolidationRelativeDepth = 0x1.0p-19;

// Groups each run of events within kConsolidationRelativeDepth * |z| of the run's first event
// into one event at that first depth with the summed count; zero sums vanish. kSampleKeys:
// the run's events all move to that depth, each sample with its net change (sorted by key).
// REQUIRES: `events` normalized as `keying` says.
std::vector<Event> ConsolidateEvents(std::span<const Event> events, EventKeying keying);

// The attenuation function of a consolidated kCounts event list: A jumps by count /
// total_samples at each event (two vertices at the event depth), and is 0 before the first.
// (Sample-keyed lists: core/events/emitter_weighting.h.)
std::vector<Vertex> FunctionFromEvents(std::span<const Event> events, int total_samples);

}  // namespace pdsm

#endif  // PDSM_CORE_EVENTS_CONSOLIDATION_H_
