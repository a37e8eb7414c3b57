// 1e5 events in one pixel, at the event / consolidation / compression / file level: a full
// bake would need a ray crossing 1e5 shadow boundaries, so the events are made directly and
// go through the same steps a tile goes through after its tasks (AssembleTile, the writer,
// the reader, the query).
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "core/pdsm/attenuation_function.h"
#include "core/pdsm/pdsm_file.h"
#include "core/pipeline/tile_assembly.h"
#include "tests/test_support.h"

namespace pdsm::extremes {
namespace {

constexpr int kEvents = 100000;
constexpr int kSamples = 65536;
constexpr int kBatches = 16;

// Event k at depth 1 + k / 1000 (spacing 1e-3, far above the consolidation distance
// 2^-19 z < 2e-4), count +-1 from a random walk that stays in [0, kSamples]. Spread over
// kBatches task results in a scrambled order.
struct Walk {
  std::vector<TileEvents> parts;
  std::vector<float> depth;
  std::vector<int64_t> hidden_after;  // samples hidden from depth[k] on
};

Walk MakeWalk() {
  Walk walk;
  std::mt19937_64 rng(5);
  std::vector<std::vector<Event>> batches(kBatches);
  int64_t hidden = 0;
  for (int k = 0; k < kEvents; ++k) {
    const float z = static_cast<float>(1.0 + k / 1000.0);
    int32_t count = (rng() & 1) ? 1 : -1;
    if (hidden + count < 0 || hidden + count > kSamples) count = -count;
    hidden += count;
    walk.depth.push_back(z);
    walk.hidden_after.push_back(hidden);
    batches[rng() % kBatches].push_back(Event{z, count});
  }
  for (int b = 0; b < kBatches; ++b) {
    TileEvents part;
    part.width = part.height = 1;
    part.offsets = {0, batches[b].size()};
    part.events = batches[b];
    NormalizeEvents(&part.events, EventKeying::kCounts);
    walk.parts.push_back(part);
  }
  return walk;
}

PdsmHeader OnePixelHeader(double epsilon) {
  PdsmHeader h;
  h.scene_name = "events";
  h.geometry.width = h.geometry.height = 1;
  h.geometry.frame.center = {0, 0, 0};
  h.geometry.z_near = 1;
  h.geometry.z_far = 101;
  h.samples = kSamples;
  h.shadow_map_resolution = 1;
  h.epsilon = epsilon;
  h.tile_size = 1;
  return h;
}

// Through assembly, the writer and the reader; the answers just after every event.
std::vector<Vertex> RoundTrip(const Walk& walk, double epsilon) {
  const PdsmHeader header = OnePixelHeader(epsilon);
  AssemblyStats stats;
  const PdsmTile tile = AssembleTile(header, walk.parts, &stats);
  EXPECT_EQ(stats.merged_events, kEvents);
  EXPECT_EQ(stats.consolidated_events, kEvents);
  pdsm::testing::TempDir dir;
  const std::string path = dir.File("events.exr");
  absl::StatusOr<std::unique_ptr<PdsmWriter>> writer = PdsmWriter::Create(path, header);
  EXPECT_TRUE(writer.ok());
  if (!writer.ok()) return {};
  EXPECT_TRUE((*writer)->WriteTile(tile).ok());
  EXPECT_TRUE((*writer)->Finish().ok());
  absl::StatusOr<PdsmImage> image = ReadPdsm(path);
  EXPECT_TRUE(image.ok()) << image.status();
  if (!image.ok()) return {};
  const auto function = image->Function(0, 0);
  return std::vector<Vertex>(function.begin(), function.end());
}

TEST(ExtremesEvents, HundredThousandEventsInOnePixelLossless) {
  const Walk walk = MakeWalk();
  const std::vector<Vertex> function = RoundTrip(walk, 0.0);
  EXPECT_EQ(function.size(), 2u * kEvents);
  double max_error = 0;
  for (int k = 0; k < kEvents; ++k) {
    const double expected = static_cast<double>(walk.hidden_after[k]) / kSamples;
    max_error =
        std::max(max_error, std::abs(EvaluateAttenuation(function, walk.depth[k]) - expected));
  }
  EXPECT_EQ(max_error, 0.0);
  EXPECT_EQ(EvaluateAttenuation(function, 0.5), 0.0f);
}

TEST(ExtremesEvents, HundredThousandEventsInOnePixelCompressed) {
  const Walk walk = MakeWalk();
  constexpr double kEpsilon = 0.01;
  const std::vector<Vertex> function = RoundTrip(walk, kEpsilon);
  std::printf("1e5 events: %zu vertices at epsilon %.2f\n", function.size(), kEpsilon);
  EXPECT_LT(function.size(), 2u * kEvents / 10);
  double max_error = 0;
  for (int k = 0; k + 1 < kEvents; ++k) {
    // A is constant between events: check just after each and halfway to the next.
    const double expected = static_cast<double>(walk.hidden_after[k]) / kSamples;
    for (double z :
         {static_cast<double>(walk.depth[k]), 0.5 * (walk.depth[k] + walk.depth[k + 1])}) {
      max_error = std::max(max_error, std::abs(EvaluateAttenuation(function, z) - expected));
    }
  }
  EXPECT_LE(max_error, kEpsilon);
}

}  // namespace
}  // namespace pdsm::extremes
