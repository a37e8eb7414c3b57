#include "rpc/tile_events_codec.h"

#include <limits>

#include <gtest/gtest.h>

namespace pdsm {
namespace {

// A 2x1 tile: pixel 0 has two events, pixel 1 none.
TileRect Tile() { return TileRect{.index = 3, .x0 = 4, .y0 = 8, .width = 2, .height = 1}; }

pdsm::v1::TileEventsData Valid() {
  pdsm::v1::TileEventsData data;
  for (uint64_t o : {0, 2, 2}) data.add_offsets(o);
  data.add_z(1.5f), data.add_count(2);
  data.add_z(2.5f), data.add_count(-2);
  return data;
}

TEST(TileEventsFromProto, DecodesAValidResult) {
  absl::StatusOr<TileEvents> events = TileEventsFromProto(Valid(), Tile());
  ASSERT_TRUE(events.ok()) << events.status();
  EXPECT_EQ(events->tile_index, 3);
  EXPECT_EQ(events->x0, 4);
  EXPECT_EQ(events->y0, 8);
  ASSERT_EQ(events->Pixel(0).size(), 2u);
  EXPECT_EQ(events->Pixel(0)[1], (Event{2.5f, -2}));
  EXPECT_TRUE(events->Pixel(1).empty());
}

void ExpectRefused(const pdsm::v1::TileEventsData& data, const std::string& field) {
  absl::StatusOr<TileEvents> events = TileEventsFromProto(data, Tile());
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

TEST(TileEventsToProto, RoundTripsThroughTheDecoder) {
  absl::StatusOr<TileEvents> events = TileEventsFromProto(Valid(), Tile());
  ASSERT_TRUE(events.ok()) << events.status();
  pdsm::v1::TileEventsData encoded;
  TileEventsToProto(*events, &encoded);
  EXPECT_EQ(encoded.SerializeAsString(), Valid().SerializeAsString());
}

}  // namespace
}  // namespace pdsm
