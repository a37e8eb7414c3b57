// A worker's task result as it arrives (pdsm.v1.TileEventsData) turned back into TileEvents,
// checked against the task's tile: a buggy or hostile worker must not crash the coordinator
// or corrupt a tile.
#ifndef PDSM_SERVER_TASK_RESULT_H_
#define PDSM_SERVER_TASK_RESULT_H_

#include "absl/status/statusor.h"
#include "core/bake/bake_plan.h"
#include "core/events/event.h"
#include "pdsm/v1/workers.pb.h"

namespace pdsm {

// INVALID_ARGUMENT naming the field when: offsets are not tile pixels + 1, do not start at 0,
// decrease or do not end at the event count; z and count differ in length; a depth is not
// finite; a pixel's depths are not strictly increasing; a count is 0.
absl::StatusOr<TileEvents> TileEventsFromProto(const pdsm::v1::TileEventsData& data,
                                               const TileRect& tile);

}  // namespace pdsm

#endif  // PDSM_SERVER_TASK_RESULT_H_
