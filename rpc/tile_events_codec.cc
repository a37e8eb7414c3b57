#include "rpc/tile_events_codec.h"

#include <bit>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <functional>
#include <string>

#include "absl/strings/str_cat.h"
#include "core/util/little_endian.h"

namespace pdsm {
namespace {

constexpr size_t kCountBytes = 4;  // event_counts: uint32 per pixel
constexpr size_t kEventBytes = 8;  // events: float32 z, int32 count
// In memory an Event is the wire's event on a little-endian machine: copied as is there.
constexpr bool kEventIsWireLayout = std::endian::native == std::endian::little &&
                                    sizeof(Event) == kEventBytes && offsetof(Event, z) == 0 &&
                                    offsetof(Event, count) == 4;

// The checks every result passes, whichever encoding brought it: finite depths from z_min on,
// increasing within a pixel, non-zero counts whose running sum stays within the batch.
// `events.offsets` are already checked (non-decreasing from 0 to the event count).
absl::Status CheckEvents(const TileEvents& events, const ResultBounds& bounds,
                         const std::function<absl::Status(const std::string&)>& bad) {
  // Events are stored as float: a depth rounded from z_min may sit just below it.
  const float z_min = std::nextafter(static_cast<float>(bounds.z_min), -1.0f);
  const size_t pixels = events.PixelCount();
  const bool keyed = bounds.keying == EventKeying::kSampleKeys;
  for (size_t p = 0; p < pixels; ++p) {
    const uint64_t begin = events.offsets[p], end = events.offsets[p + 1];
    int64_t shadowed = 0;
    for (uint64_t e = begin; e < end; ++e) {
      const float z = events.events[e].z;
      const int32_t count = events.events[e].count;
      if (!std::isfinite(z)) return bad(absl::StrCat("z[", e, "]: must be finite"));
      if (z < z_min) {
        return bad(absl::StrCat("z[", e, "]: nearer than the plan's rays start (", z, " < ",
                                bounds.z_min, ")"));
      }
      if (count == 0) return bad(absl::StrCat("count[", e, "]: must not be 0"));
      if (e > begin) {
        const Event& before = events.events[e - 1];
        if (keyed ? !KeyedBefore(before, events.events[e]) : !(z > before.z)) {
          return bad(absl::StrCat("z[", e, "]: ", keyed ? "(depth, key)" : "depths", " of pixel ",
                                  p, " must increase"));
        }
      }
      if (keyed) {
        const int64_t sample = SampleOfEvent(events.events[e]);
        if (sample < bounds.sample_begin || sample >= bounds.sample_begin + bounds.batch_samples) {
          return bad(absl::StrCat("count[", e, "]: sample ", sample, " is not of the batch [",
                                  bounds.sample_begin, ", ",
                                  bounds.sample_begin + bounds.batch_samples, ")"));
        }
      }
      shadowed += ShadowChange(events.events[e], bounds.keying);
      if (shadowed < 0 || shadowed > bounds.batch_samples) {
        return bad(absl::StrCat("count[", e, "]: pixel ", p, " would have ", shadowed,
                                " shadowed samples of a batch of ", bounds.batch_samples));
      }
    }
  }
  return absl::OkStatus();
}

// Fields 1-3 (workers of builds before 2026-12-06).
absl::Status DecodeColumns(const pdsm::v1::TileEventsData& data, size_t pixels,
                           const std::function<absl::Status(const std::string&)>& bad,
                           TileEvents* events) {
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
  for (size_t p = 0; p < pixels; ++p) {
    if (data.offsets(static_cast<int>(p + 1)) < data.offsets(static_cast<int>(p))) {
      return bad(absl::StrCat("offsets[", p + 1, "]: decreases"));
    }
  }
  events->offsets.assign(data.offsets().begin(), data.offsets().end());
  events->events.resize(data.z_size());
  for (int e = 0; e < data.z_size(); ++e) events->events[e] = Event{data.z(e), data.count(e)};
  return absl::OkStatus();
}

// Fields 4-5.
absl::Status DecodeArrays(const pdsm::v1::TileEventsData& data, size_t pixels,
                          const std::function<absl::Status(const std::string&)>& bad,
                          TileEvents* events) {
  events->offsets.assign(pixels + 1, 0);
  if (data.event_counts().empty()) {
    if (!data.events().empty()) return bad("events: given, but event_counts counts none");
    return absl::OkStatus();
  }
  if (data.event_counts().size() != pixels * kCountBytes) {
    return bad(absl::StrCat("event_counts: must be ", pixels * kCountBytes,
                            " bytes, 4 per tile pixel (got ", data.event_counts().size(), ")"));
  }
  ByteReader counts(data.event_counts().data());
  uint64_t total = 0;  // at most 2^32 * pixels: no overflow
  for (size_t p = 0; p < pixels; ++p) {
    total += counts.U32();
    events->offsets[p + 1] = total;
  }
  if (total != data.events().size() / kEventBytes || data.events().size() % kEventBytes != 0) {
    return bad(absl::StrCat("events: must be ", total * kEventBytes, " bytes, 8 per event (got ",
                            data.events().size(), ")"));
  }
  events->events.resize(total);
  if (total == 0) return absl::OkStatus();  // memcpy takes no null pointer, even for 0 bytes
  if constexpr (kEventIsWireLayout) {
    std::memcpy(events->events.data(), data.events().data(), data.events().size());
  } else {
    ByteReader in(data.events().data());
    for (Event& e : events->events) {
      e.z = in.F32();
      e.count = in.I32();
    }
  }
  return absl::OkStatus();
}

}  // namespace

void TileEventsToProto(const TileEvents& events, pdsm::v1::TileEventsData* data) {
  if (events.events.empty()) return;  // both fields empty: no pixel has an event
  const size_t pixels = events.PixelCount();
  std::string* counts = data->mutable_event_counts();
  counts->resize(pixels * kCountBytes);
  ByteWriter out_counts(counts->data());
  for (size_t p = 0; p < pixels; ++p) {
    out_counts.U32(static_cast<uint32_t>(events.offsets[p + 1] - events.offsets[p]));
  }
  std::string* bytes = data->mutable_events();
  bytes->resize(events.events.size() * kEventBytes);
  if constexpr (kEventIsWireLayout) {
    std::memcpy(bytes->data(), events.events.data(), bytes->size());
  } else {
    ByteWriter out(bytes->data());
    for (const Event& e : events.events) {
      out.F32(e.z);
      out.I32(e.count);
    }
  }
}

absl::StatusOr<TileEvents> TileEventsFromProto(const pdsm::v1::TileEventsData& data,
                                               const TileRect& tile, const ResultBounds& bounds) {
  const size_t pixels = static_cast<size_t>(tile.width) * tile.height;
  const std::function<absl::Status(const std::string&)> bad = [&](const std::string& what) {
    return absl::InvalidArgumentError(absl::StrCat("events (tile ", tile.index, "): ", what));
  };
  TileEvents events;
  events.tile_index = tile.index;
  events.x0 = tile.x0;
  events.y0 = tile.y0;
  events.width = tile.width;
  events.height = tile.height;
  const bool columns = data.offsets_size() > 0 || data.z_size() > 0 || data.count_size() > 0;
  const bool arrays = !data.event_counts().empty() || !data.events().empty();
  if (columns && arrays) {
    return bad("offsets, z and count and event_counts and events: one encoding, not both");
  }
  if (absl::Status s = columns ? DecodeColumns(data, pixels, bad, &events)
                               : DecodeArrays(data, pixels, bad, &events);
      !s.ok()) {
    return s;
  }
  if (absl::Status s = CheckEvents(events, bounds, bad); !s.ok()) return s;
  return events;
}

}  // namespace pdsm
