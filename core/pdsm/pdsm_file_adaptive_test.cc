// Adaptive bakes' header attributes (pdsmAdaptiveTolerance, pdsmAdaptiveMinSamples,
// pdsmTileSamples): written after the tiles, read back per tile, absent from fixed bakes.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "core/pdsm/pdsm_file.h"
#include "core/util/file_system.h"
#include "tests/test_support.h"
#include "tests/write_faults.h"

namespace pdsm {
namespace {

PdsmHeader SmallHeader() {
  PdsmHeader h;
  h.scene_name = "adaptive";
  h.geometry.width = 5;
  h.geometry.height = 3;
  h.geometry.z_near = 1;
  h.geometry.z_far = 2;
  h.samples = 64;
  h.tile_size = 2;  // 3 x 2 tiles, the last column and row partial
  return h;
}

// Tile t (row-major) gets one lit-then-shadowed pixel function.
std::vector<PdsmTile> Tiles(const PdsmHeader& h, const std::vector<int>& samples) {
  std::vector<PdsmTile> tiles;
  int t = 0;
  for (int y0 = 0; y0 < h.geometry.height; y0 += h.tile_size) {
    for (int x0 = 0; x0 < h.geometry.width; x0 += h.tile_size, ++t) {
      PdsmTile tile;
      tile.x0 = x0;
      tile.y0 = y0;
      tile.width = std::min(h.tile_size, h.geometry.width - x0);
      tile.height = std::min(h.tile_size, h.geometry.height - y0);
      tile.samples = samples[t];
      tile.vertices = {{1.5f, 0.0f}, {1.5f, 1.0f / samples[t]}};
      tile.offsets.assign(tile.width * tile.height + 1, 2);
      tile.offsets[0] = 0;
      tiles.push_back(tile);
    }
  }
  return tiles;
}

absl::Status Write(const std::string& path, const PdsmHeader& h, const std::vector<PdsmTile>& tiles,
                   bool reversed, FileSystem* file_system = nullptr) {
  absl::StatusOr<std::unique_ptr<PdsmWriter>> writer = PdsmWriter::Create(path, h, file_system);
  if (!writer.ok()) return writer.status();
  for (size_t k = 0; k < tiles.size(); ++k) {
    const PdsmTile& tile = tiles[reversed ? tiles.size() - 1 - k : k];
    if (absl::Status s = (*writer)->WriteTile(tile); !s.ok()) return s;
  }
  return (*writer)->Finish();
}

TEST(PdsmFileAdaptiveTest, RoundTripsPerTileSampleCounts) {
  testing::TempDir dir;
  PdsmHeader h = SmallHeader();
  h.adaptive_tolerance = 0.02;
  h.adaptive_min_samples = 16;
  const std::vector<int> counts = {16, 64, 32, 16, 64, 1};
  const std::string path = dir.File("a.exr");
  ASSERT_TRUE(Write(path, h, Tiles(h, counts), false).ok());
  absl::StatusOr<PdsmImage> image = ReadPdsm(path);
  ASSERT_TRUE(image.ok()) << image.status();
  EXPECT_EQ(image->header.adaptive_tolerance, 0.02);
  EXPECT_EQ(image->header.adaptive_min_samples, 16);
  EXPECT_EQ(image->header.tile_samples, counts);
  EXPECT_EQ(image->header.TileSamples(1), 64);
  EXPECT_EQ(image->Function(2, 0)[1].a, 1.0f / 64);
  // Two temporary files (the first pass, then the copy with the counts): only the copy's
  // rename leaves anything.
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path()), {}), 1);

  // Byte-identical whatever the tile order.
  const std::string reversed = dir.File("b.exr");
  ASSERT_TRUE(Write(reversed, h, Tiles(h, counts), true).ok());
  EXPECT_EQ(testing::ReadBytes(path), testing::ReadBytes(reversed));
}

TEST(PdsmFileAdaptiveTest, FixedBakesHaveNoTileCounts) {
  testing::TempDir dir;
  const PdsmHeader h = SmallHeader();
  const std::string path = dir.File("f.exr");
  ASSERT_TRUE(Write(path, h, Tiles(h, std::vector<int>(6, 64)), false).ok());
  absl::StatusOr<PdsmImage> image = ReadPdsm(path);
  ASSERT_TRUE(image.ok()) << image.status();
  EXPECT_FALSE(image->header.adaptive());
  EXPECT_TRUE(image->header.tile_samples.empty());
  EXPECT_EQ(image->header.TileSamples(3), 64);
  EXPECT_EQ(testing::ReadBytes(path).find("pdsmTileSamples"), std::string::npos);
}

// The adaptive writer's second pass (read back the first temporary file, copy it into a
// second one) fails cleanly too: at every write, flush, sync, rename and on a full disk.
TEST(PdsmFileAdaptiveTest, EveryFileSystemFailureLeavesThePreviousPdsm) {
  testing::TempDir dir;
  PdsmHeader h = SmallHeader();
  h.adaptive_tolerance = 0.02;
  h.adaptive_min_samples = 16;
  const std::string path = dir.File("a.exr");
  ASSERT_TRUE(Write(path, h, Tiles(h, {16, 64, 32, 16, 64, 1}), false).ok());
  const std::string previous = testing::ReadBytes(path);
  testing::ExpectWriteFailuresLeaveTargetIntact(path, dir.path(), [&](FileSystem* file_system) {
    return Write(path, h, Tiles(h, {64, 64, 32, 16, 64, 2}), true, file_system);
  });
  EXPECT_EQ(testing::ReadBytes(path), previous);
}

TEST(PdsmFileAdaptiveTest, TileCountOutOfRangeIsRejected) {
  testing::TempDir dir;
  PdsmHeader h = SmallHeader();
  h.adaptive_tolerance = 0.1;
  h.adaptive_min_samples = 4;
  std::vector<PdsmTile> tiles = Tiles(h, {4, 4, 4, 4, 4, 4});
  tiles[2].samples = 65;  // above header.samples
  const absl::Status s = Write(dir.File("c.exr"), h, tiles, false);
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument) << s;
  EXPECT_FALSE(std::filesystem::exists(dir.File("c.exr")));
}

}  // namespace
}  // namespace pdsm
