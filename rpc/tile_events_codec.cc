#include "rpc/tile_events_codec.h"

#include <cmath>

#include "absl/strings/str_cat.h"

namespace pdsm {

void TileEventsToProto(const TileEvents& events, pdsm::v1::TileEventsData* data) {
  data->mutable_offsets()->Assign(events.offsets.begin(), events.offsets.end());
  data->mutable_z()->Reserve(static_cast<int>(events.events.size()));
  data->mutable_count()->Reserve(static_cast<int>(events.events.size()));
  for (const Event& e : events.events) {
    data->add_z(e.z);
    data->add_count(e.count);
  }
}

absl::StatusOr<TileEvents> TileEventsFromProto(const pdsm::v1::TileEventsData& data,
                                               const TileRect& tile, const ResultBounds& bounds) {
  const size_t pixels = static_cast<size_t>(tile.width) * tile.height;
  const auto bad = [&](const std::string& what) {
    return absl::InvalidArgumentError(absl::StrCat("events (tile ", tile.index, "): ", what));
  };
  if (static_cast<size_t>(data.offsets_size()) != pixels + 1) {
    return bad(absl::StrCat("offsets: must have ", pixels + 1, " entries (got ",
                            data.offsets_size(), ")"));
  }
  if (data.z_size() != data.count_size()) {
    return bad(absl::StrCat("z and count differ in length (", data.z_size(), " and ",
                            data.count_size(), ")"));
  }
  if (data.offsets(0) != 0 ||
      data.offsets(static_cast<int>(pixels)) != static_cast<uint64_t>(data.z_size())) {
    return bad("offsets: must start at 0 and end at the event count");
  }
  // Offsets first: non-decreasing up to the event count keeps every read below in range.
  for (size_t p = 0; p < pixels; ++p) {
    if (data.offsets(static_cast<int>(p + 1)) < data.offsets(static_cast<int>(p))) {
      return bad(absl::StrCat("offsets[", p + 1, "]: decreases"));
    }
  }
  TileEvents events;
  events.tile_index = tile.index;
  events.x0 = tile.x0;
  events.y0 = tile.y0;
  events.width = tile.width;
  events.height = tile.height;
  events.offsets.assign(data.offsets().begin(), data.offsets().end());
  events.events.reserve(data.z_size());
  // Events are stored as float: a depth rounded from z_min may sit just below it.
  const float z_min = std::nextafter(static_cast<float>(bounds.z_min), -1.0f);
  for (size_t p = 0; p < pixels; ++p) {
    const uint64_t begin = events.offsets[p], end = events.offsets[p + 1];
    int64_t shadowed = 0;
    for (uint64_t e = begin; e < end; ++e) {
      const float z = data.z(static_cast<int>(e));
      const int32_t count = data.count(static_cast<int>(e));
      if (!std::isfinite(z)) return bad(absl::StrCat("z[", e, "]: must be finite"));
      if (z < z_min) {
        return bad(absl::StrCat("z[", e, "]: nearer than the plan's rays start (", z, " < ",
                                bounds.z_min, ")"));
      }
      if (e > begin && !(z > events.events.back().z)) {
        return bad(absl::StrCat("z[", e, "]: depths of pixel ", p, " must increase"));
      }
      if (count == 0) return bad(absl::StrCat("count[", e, "]: must not be 0"));
      shadowed += count;
      if (shadowed < 0 || shadowed > bounds.batch_samples) {
        return bad(absl::StrCat("count[", e, "]: pixel ", p, " would have ", shadowed,
                                " shadowed samples of a batch of ", bounds.batch_samples));
      }
      events.events.push_back(Event{z, count});
    }
  }
  return events;
}

}  // namespace pdsm
