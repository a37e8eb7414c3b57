#include "rpc/tile_events_codec.h"

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace pdsm {
namespace {

// A 2x1 tile: pixel 0 has two events, pixel 1 none.
TileRect Tile() { return TileRect{.index = 3, .x0 = 4, .y0 = 8, .width = 2, .height = 1}; }

// A batch of 2 samples; rays start at depth 1.
ResultBounds Bounds() { return ResultBounds{.batch_samples = 2, .z_min = 1.0}; }

pdsm::v1::TileEventsData Valid() {
  pdsm::v1::TileEventsData data;
  for (uint64_t o : {0, 2, 2}) data.add_offsets(o);
  data.add_z(1.5f), data.add_count(2);
  data.add_z(2.5f), data.add_count(-2);
  return data;
}

TEST(TileEventsFromProto, DecodesAValidResult) {
  absl::StatusOr<TileEvents> events = TileEventsFromProto(Valid(), Tile(), Bounds());
  ASSERT_TRUE(events.ok()) << events.status();
  EXPECT_EQ(events->tile_index, 3);
  EXPECT_EQ(events->x0, 4);
  EXPECT_EQ(events->y0, 8);
  ASSERT_EQ(events->Pixel(0).size(), 2u);
  EXPECT_EQ(events->Pixel(0)[1], (Event{2.5f, -2}));
  EXPECT_TRUE(events->Pixel(1).empty());
}

void ExpectRefused(const pdsm::v1::TileEventsData& data, const std::string& field) {
  absl::StatusOr<TileEvents> events = TileEventsFromProto(data, Tile(), Bounds());
  ASSERT_EQ(events.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(events.status().message().find(field), std::string::npos) << events.status();
}

TEST(TileEventsFromProto, RefusesWhatDoesNotFitTheTile) {
  pdsm::v1::TileEventsData data = Valid();
  data.add_offsets(2);
  ExpectRefused(data, "offsets");  // one pixel too many

  data = Valid();
  data.add_z(3.0f);
  ExpectRefused(data, "z and count");

  data = Valid();
  data.set_offsets(2, 1);
  ExpectRefused(data, "offsets");  // does not end at the event count

  data = Valid();
  data.set_offsets(1, 3);
  data.set_offsets(2, 2);
  ExpectRefused(data, "offsets");  // decreases (and would read past pixel 0's events)

  data = Valid();
  data.set_z(1, std::numeric_limits<float>::quiet_NaN());
  ExpectRefused(data, "z[1]");

  data = Valid();
  data.set_z(1, 1.0f);
  ExpectRefused(data, "must increase");

  data = Valid();
  data.set_count(0, 0);
  ExpectRefused(data, "count[0]");
}

// Issue #17 finding 3: well-formed results a correct worker cannot produce.
TEST(TileEventsFromProto, RefusesCountsAndDepthsNoBakeCanProduce) {
  pdsm::v1::TileEventsData data = Valid();
  data.set_count(0, std::numeric_limits<int32_t>::max());
  ExpectRefused(data, "count[0]: pixel 0 would have 2147483647 shadowed samples");

  data = Valid();
  data.set_count(0, -5);
  ExpectRefused(data, "count[0]");  // below zero at once

  data = Valid();
  data.set_count(0, 3);  // more samples than the batch has
  ExpectRefused(data, "count[0]");

  data = Valid();
  data.set_count(1, -3);  // leaves more samples than entered
  ExpectRefused(data, "count[1]");

  data = Valid();
  data.set_z(0, -1.5f);
  ExpectRefused(data, "z[0]: nearer than the plan's rays start");

  // A depth at the start of the rays, rounded to float below it, is a real event.
  data = Valid();
  data.set_z(0, std::nextafter(1.0f, 0.0f));
  EXPECT_TRUE(TileEventsFromProto(data, Tile(), Bounds()).ok());

  // Ending shadowed (an open ray behind the last occluder) is within the bounds.
  data = Valid();
  data.set_count(1, -1);
  EXPECT_TRUE(TileEventsFromProto(data, Tile(), Bounds()).ok());
}

// Sample-keyed results (an emitter-weighted plan): a batch of samples 4 and 5 (keys 5, 6).
TEST(TileEventsFromProto, SampleKeyedResultsAreOrderedByDepthAndKeyAndOfTheBatch) {
  const ResultBounds keyed{
      .batch_samples = 2, .z_min = 1.0, .keying = EventKeying::kSampleKeys, .sample_begin = 4};
  pdsm::v1::TileEventsData data;
  for (uint64_t o : {0, 4, 4}) data.add_offsets(o);
  // Both samples enter at one depth (two events there), then leave.
  data.add_z(1.5f), data.add_count(5);
  data.add_z(1.5f), data.add_count(6);
  data.add_z(2.5f), data.add_count(-6);
  data.add_z(3.5f), data.add_count(-5);
  absl::StatusOr<TileEvents> events = TileEventsFromProto(data, Tile(), keyed);
  ASSERT_TRUE(events.ok()) << events.status();
  EXPECT_EQ(events->Pixel(0)[1], (Event{1.5f, 6}));
  // Counted, two events at one depth are malformed.
  EXPECT_FALSE(TileEventsFromProto(data, Tile(), Bounds()).ok());

  auto refused = [&](const pdsm::v1::TileEventsData& bad, const std::string& field) {
    absl::StatusOr<TileEvents> r = TileEventsFromProto(bad, Tile(), keyed);
    ASSERT_EQ(r.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_NE(r.status().message().find(field), std::string::npos) << r.status();
  };
  pdsm::v1::TileEventsData swapped = data;  // keys at one depth out of order
  swapped.set_count(0, 6), swapped.set_count(1, 5);
  refused(swapped, "(depth, key) of pixel 0 must increase");
  pdsm::v1::TileEventsData foreign = data;  // sample 3 is another batch's
  foreign.set_count(0, 4), foreign.set_count(3, -4);
  refused(foreign, "sample 3 is not of the batch [4, 6)");
  pdsm::v1::TileEventsData lowest = data;  // a key no sample has, whose negation overflows
  lowest.set_count(3, std::numeric_limits<int32_t>::min());
  refused(lowest, "count[3]");
}

// Valid() in the fixed-width encoding a worker sends (fields 4-5).
pdsm::v1::TileEventsData ValidArrays() {
  pdsm::v1::TileEventsData data;
  data.set_event_counts(std::string("\2\0\0\0\0\0\0\0", 8));
  const float z[2] = {1.5f, 2.5f};
  const int32_t count[2] = {2, -2};
  std::string events;
  for (int e = 0; e < 2; ++e) {
    events.append(reinterpret_cast<const char*>(&z[e]), 4);  // the test runs little-endian
    events.append(reinterpret_cast<const char*>(&count[e]), 4);
  }
  data.set_events(events);
  return data;
}

TEST(TileEventsToProto, WritesTheFixedWidthEncodingWhichDecodesToTheSameEvents) {
  absl::StatusOr<TileEvents> events = TileEventsFromProto(Valid(), Tile(), Bounds());
  ASSERT_TRUE(events.ok()) << events.status();
  pdsm::v1::TileEventsData encoded;
  TileEventsToProto(*events, &encoded);
  EXPECT_EQ(encoded.SerializeAsString(), ValidArrays().SerializeAsString());
  EXPECT_EQ(encoded.offsets_size() + encoded.z_size() + encoded.count_size(), 0);
  absl::StatusOr<TileEvents> decoded = TileEventsFromProto(encoded, Tile(), Bounds());
  ASSERT_TRUE(decoded.ok()) << decoded.status();
  EXPECT_EQ(decoded->offsets, events->offsets);
  EXPECT_EQ(decoded->events, events->events);

  // A tile without events is two empty fields, and decodes to empty lists.
  TileEvents empty = *events;
  empty.events.clear();
  empty.offsets.assign(3, 0);
  pdsm::v1::TileEventsData none;
  TileEventsToProto(empty, &none);
  EXPECT_EQ(none.ByteSizeLong(), 0u);
  absl::StatusOr<TileEvents> decoded_none = TileEventsFromProto(none, Tile(), Bounds());
  ASSERT_TRUE(decoded_none.ok()) << decoded_none.status();
  EXPECT_EQ(decoded_none->offsets, (std::vector<uint64_t>{0, 0, 0}));
  EXPECT_TRUE(decoded_none->events.empty());
}

TEST(TileEventsFromProto, RefusesFixedWidthArraysThatDoNotFitTheTileOrTheirCounts) {
  pdsm::v1::TileEventsData data = ValidArrays();
  data.mutable_event_counts()->append(std::string(4, '\0'));  // one pixel too many
  ExpectRefused(data, "event_counts: must be 8 bytes");

  data = ValidArrays();
  data.mutable_events()->pop_back();
  ExpectRefused(data, "events: must be 16 bytes");

  data = ValidArrays();
  (*data.mutable_event_counts())[0] = 3;  // counts an event the bytes do not hold
  ExpectRefused(data, "events: must be 24 bytes");

  data = ValidArrays();
  (*data.mutable_event_counts())[3] = '\x7f';  // 2^30 events: refused before allocating
  ExpectRefused(data, "events: must be");

  data = ValidArrays();
  data.clear_event_counts();
  ExpectRefused(data, "event_counts counts none");

  // Counts of zero only, and no events: an empty tile, however it was spelled (found by
  // fuzz_task_result: it copied zero bytes to a null pointer).
  data = ValidArrays();
  data.set_event_counts(std::string(8, '\0'));
  data.clear_events();
  absl::StatusOr<TileEvents> zeros = TileEventsFromProto(data, Tile(), Bounds());
  ASSERT_TRUE(zeros.ok()) << zeros.status();
  EXPECT_TRUE(zeros->events.empty());

  data = ValidArrays();
  data.add_offsets(0);
  ExpectRefused(data, "not both");

  // The checks on depths and counts hold in this encoding too.
  data = ValidArrays();
  const int32_t too_many = 3;
  data.mutable_events()->replace(4, 4, reinterpret_cast<const char*>(&too_many), 4);
  ExpectRefused(data, "count[0]: pixel 0 would have 3 shadowed samples");

  data = ValidArrays();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  data.mutable_events()->replace(8, 4, reinterpret_cast<const char*>(&nan), 4);
  ExpectRefused(data, "z[1]: must be finite");
}

}  // namespace
}  // namespace pdsm
