// A worker's result (rpc/tile_events_codec.h, decoding only): the protobuf bytes a hostile
// worker could send, decoded against a tile. The first byte picks the tile's size, so that
// offsets of every length get tried. Each input is decoded as counted events and as the
// sample-keyed events of an emitter-weighted plan.
#include <cstddef>
#include <cstdint>

#include "pdsm/v1/workers.pb.h"
#include "rpc/tile_events_codec.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  pdsm::TileRect tile;
  tile.index = 3;
  tile.x0 = 16;
  tile.y0 = 8;
  tile.width = 1 + data[0] % 8;
  tile.height = 1 + (data[0] / 8) % 8;
  pdsm::v1::TileEventsData events;
  if (!events.ParseFromArray(data + 1, static_cast<int>(size - 1))) return 0;
  const pdsm::ResultBounds bounds{.batch_samples = 1 + data[0] % 64, .z_min = 0.5};
  pdsm::TileEventsFromProto(events, tile, bounds).status().IgnoreError();
  const pdsm::ResultBounds keyed{.batch_samples = 1 + data[0] % 64,
                                 .z_min = 0.5,
                                 .keying = pdsm::EventKeying::kSampleKeys,
                                 .sample_begin = data[0] / 4};
  pdsm::TileEventsFromProto(events, tile, keyed).status().IgnoreError();
  return 0;
}
