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

// Fills `data` with the events' offsets and (z, count) columns.
void TileEventsToProto(const TileEvents& events, pdsm::v1::TileEventsData* data);

// INVALID_ARGUMENT naming the field when: offsets are not tile pixels + 1, do not start at 0,
// decrease or do not end at the event count; z and count differ in length; a depth is not
// finite; a pixel's depths are not strictly increasing; a count is 0.
absl::StatusOr<TileEvents> TileEventsFromProto(const pdsm::v1::TileEventsData& data,
                                               const TileRect& tile);

}  // namespace pdsm

#endif  // PDSM_RPC_TILE_EVENTS_CODEC_H_
