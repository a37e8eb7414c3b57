// A task result on the wire (pdsm.v1.TileEventsData): the worker encodes its TileEvents, the
// coordinator decodes them checked against the task's tile, so that a buggy or hostile worker
// cannot crash the coordinator or corrupt a tile.
#ifndef PDSM_RPC_TILE_EVENTS_CODEC_H_
#define PDSM_RPC_TILE_EVENTS_CODEC_H_

#include "absl/status/statusor.h"
#include "core/bake/bake_plan.h"
#include "core/events/event.h"
#include "pdsm/v1/workers.pb.h"

namespace pdsm {

// Fills `data` with the events in the fixed-width encoding (fields 4-5).
void TileEventsToProto(const TileEvents& events, pdsm::v1::TileEventsData* data);

// What a correct result of one task can hold (the plan and the lease say it): each pixel's
// running count of shadowed samples stays within [0, batch_samples] after every event (a
// sample enters at most once before it leaves), and every depth is at least z_min, the
// nearest depth any ray of the plan starts at (BakePlan::z_clip_near: tile reach clips every
// ray there, and scan conversion emits nothing before a ray's start). Sample-keyed events
// (an emitter-weighted plan, core/events/event.h) are ordered by (depth, key) instead of by
// distinct depths, and each names a sample of the batch, [sample_begin, sample_end).
struct ResultBounds {
  int batch_samples = 0;                      // Task.sample_end - Task.sample_begin
  double z_min = 0;                           // world units, light space
  EventKeying keying = EventKeying::kCounts;  // KeyingOf(plan.header)
  int sample_begin = 0;                       // kSampleKeys: Task.sample_begin
};

// Reads either encoding. INVALID_ARGUMENT naming the field when: both encodings are present;
// event_counts is not empty or 4 bytes per tile pixel, or events is not 8 bytes per event it
// counts; offsets are not tile pixels + 1, do not start at 0,
// decrease or do not end at the event count; z and count differ in length; a depth is not
// finite, is nearer than bounds.z_min, or a pixel's depths are not strictly increasing
// (kSampleKeys: its (depth, key) pairs); a count is 0 or takes the pixel's running sum (of
// ShadowChange) outside [0, bounds.batch_samples]; a kSampleKeys key names a sample outside the
// batch. The last two are what keeps a forged but well-formed result (issue #17: counts of
// +2147483647 or -5, negative depths) out of a PDSM.
absl::StatusOr<TileEvents> TileEventsFromProto(const pdsm::v1::TileEventsData& data,
                                               const TileRect& tile, const ResultBounds& bounds);

}  // namespace pdsm

#endif  // PDSM_RPC_TILE_EVENTS_CODEC_H_
