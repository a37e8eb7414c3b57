#include "core/pdsm/tile_reorder_buffer.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cerrno>
#include <random>
#include <vector>

#include "core/pdsm/pdsm_test_images.h"
#include "core/util/fault_injecting_file_system.h"
#include "tests/test_support.h"

namespace pdsm {
namespace {

using ::pdsm::testing::ExpectSameTile;

// A tile of `side` x `side` pixels at tile (i, 0) with 0 to 5 random vertices a pixel.
PdsmTile RandomTile(int i, int side, uint32_t seed) {
  std::mt19937 rng(seed);
  PdsmTile tile;
  tile.x0 = i * side;
  tile.width = tile.height = side;
  tile.samples = 1 + i % 7;
  tile.offsets.push_back(0);
  for (int p = 0; p < side * side; ++p) {
    const int n = static_cast<int>(rng() % 6);
    for (int k = 0; k < n; ++k) {
      tile.vertices.push_back(
          {static_cast<float>(rng() % 1000) / 7.0f, static_cast<float>(rng() % 101) / 100.0f});
    }
    tile.offsets.push_back(tile.vertices.size());
  }
  return tile;
}

PdsmTile EmptyTile(int i, int side) {
  PdsmTile tile;
  tile.x0 = i * side;
  tile.width = tile.height = side;
  tile.offsets.assign(static_cast<size_t>(side) * side + 1, 0);
  return tile;
}

// The all-lit tiles of a sparse world cost their rectangle, not 8 bytes a pixel.
TEST(TileReorderBuffer, EmptyTilesHoldNoHeapAndComeBackWhole) {
  testing::TempDir dir;
  TileReorderBuffer buffer(dir.path().string(), /*memory_budget_bytes=*/0);
  for (int i = 0; i < 1000; ++i) ASSERT_TRUE(buffer.Put(i, EmptyTile(i, 64)).ok());
  EXPECT_EQ(buffer.size(), 1000u);
  EXPECT_EQ(buffer.memory_bytes(), 0);
  EXPECT_EQ(buffer.spilled_bytes(), 0);
  for (int i = 999; i >= 0; --i) {
    absl::StatusOr<std::optional<PdsmTile>> tile = buffer.Take(i);
    ASSERT_TRUE(tile.ok()) << tile.status();
    ASSERT_TRUE(tile->has_value());
    ExpectSameTile(**tile, EmptyTile(i, 64));
  }
  EXPECT_EQ(buffer.size(), 0u);
}

TEST(TileReorderBuffer, PastTheBudgetTilesGoToDiskAndComeBackBitForBit) {
  testing::TempDir dir;
  constexpr int64_t kBudget = 40 << 10;
  TileReorderBuffer buffer(dir.path().string(), kBudget);
  std::vector<PdsmTile> tiles;
  for (int i = 0; i < 40; ++i) tiles.push_back(RandomTile(i, 16, 100 + i));
  for (int i = 0; i < 40; ++i) {
    ASSERT_TRUE(buffer.Put(i, tiles[i]).ok());
    EXPECT_LE(buffer.memory_bytes(), kBudget);
  }
  EXPECT_GT(buffer.memory_bytes(), 0);
  EXPECT_GT(buffer.spilled_bytes(), 0);
  // The scratch file has no name: nothing in the folder.
  EXPECT_TRUE(std::filesystem::is_empty(dir.path()));

  std::vector<int> order(40);
  for (int i = 0; i < 40; ++i) order[i] = i;
  std::shuffle(order.begin(), order.end(), std::mt19937(7));
  for (int i : order) {
    EXPECT_TRUE(buffer.Contains(i));
    absl::StatusOr<std::optional<PdsmTile>> tile = buffer.Take(i);
    ASSERT_TRUE(tile.ok()) << tile.status();
    ASSERT_TRUE(tile->has_value());
    ExpectSameTile(**tile, tiles[i]);
    EXPECT_FALSE(buffer.Contains(i));
  }
  EXPECT_EQ(buffer.memory_bytes(), 0);
  EXPECT_EQ(buffer.spilled_bytes(), 0);
  absl::StatusOr<std::optional<PdsmTile>> none = buffer.Take(3);
  ASSERT_TRUE(none.ok());
  EXPECT_FALSE(none->has_value());
}

TEST(TileReorderBuffer, ASpillThatCannotBeWrittenIsTheDisksErrorAndKeepsNothing) {
  testing::TempDir dir;
  FaultInjectingFileSystem faults;
  TileReorderBuffer buffer(dir.path().string(), /*memory_budget_bytes=*/0, &faults);
  faults.SetDiskFullAfter(1000);
  const absl::Status full = buffer.Put(0, RandomTile(0, 32, 1));
  EXPECT_EQ(full.code(), absl::StatusCode::kResourceExhausted) << full;
  EXPECT_THAT(std::string(full.message()), ::testing::HasSubstr(dir.path().string()));
  EXPECT_FALSE(buffer.Contains(0));
  EXPECT_EQ(buffer.spilled_bytes(), 0);
}

}  // namespace
}  // namespace pdsm
