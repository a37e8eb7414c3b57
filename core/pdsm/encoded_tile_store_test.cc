#include "core/pdsm/encoded_tile_store.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <memory>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "core/pdsm/pdsm_file.h"
#include "core/pdsm/pdsm_test_images.h"
#include "tests/test_support.h"

namespace pdsm {
namespace {

using ::pdsm::testing::CutTiles;
using ::pdsm::testing::FullHeader;
using ::pdsm::testing::RandomImage;
using ::pdsm::testing::ReadBytes;
using ::pdsm::testing::TempDir;
using ::pdsm::testing::WriteTiles;
using ::testing::HasSubstr;

// Every fourth tile without a vertex, as a sparse world's are.
std::vector<PdsmTile> TilesWithEmptyOnes(const PdsmHeader& header, uint32_t seed) {
  std::vector<PdsmTile> tiles = CutTiles(RandomImage(header, seed));
  for (size_t i = 0; i < tiles.size(); i += 4) {
    tiles[i].vertices.clear();
    std::fill(tiles[i].offsets.begin(), tiles[i].offsets.end(), 0);
  }
  return tiles;
}

TEST(EncodedTileStoreTest, TilesPutFromThreadsInAnyOrderMakeTheFileWriteTileMakes) {
  TempDir dir;
  const PdsmHeader header = FullHeader(150, 70, 16);
  std::vector<PdsmTile> tiles = TilesWithEmptyOnes(header, 31);
  const std::string direct = (dir.path() / "direct.exr").string();
  ASSERT_TRUE(WriteTiles(direct, header, tiles).ok());

  std::shuffle(tiles.begin(), tiles.end(), std::mt19937(4));
  EncodedTileStore store(header, (dir.path() / "out.exr").string());
  std::vector<std::thread> threads;
  for (int t = 0; t < 3; ++t) {
    threads.emplace_back([&, t] {
      for (size_t i = t; i < tiles.size(); i += 3) EXPECT_TRUE(store.Put(tiles[i]).ok());
    });
  }
  for (std::thread& thread : threads) thread.join();
  const std::string stored = (dir.path() / "stored.exr").string();
  absl::StatusOr<std::unique_ptr<PdsmWriter>> writer = PdsmWriter::Create(stored, header);
  ASSERT_TRUE(writer.ok());
  ASSERT_TRUE(store.WriteTo(writer->get()).ok());
  ASSERT_TRUE((*writer)->Finish().ok());
  EXPECT_EQ(ReadBytes(stored), ReadBytes(direct));
}

TEST(EncodedTileStoreTest, RefusesWhatIsNotOneOfItsTilesOnce) {
  TempDir dir;
  const PdsmHeader header = FullHeader(40, 40, 16);
  const std::vector<PdsmTile> tiles = TilesWithEmptyOnes(header, 5);
  EncodedTileStore store(header, (dir.path() / "out.exr").string());
  ASSERT_TRUE(store.Put(tiles[1]).ok());
  absl::Status twice = store.Put(tiles[1]);
  EXPECT_EQ(twice.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(twice.message(), HasSubstr("twice"));
  PdsmTile shifted = tiles[2];
  shifted.x0 += 1;
  EXPECT_EQ(store.Put(shifted).code(), absl::StatusCode::kInvalidArgument);
  PdsmTile decreasing = tiles[2];
  ASSERT_GE(decreasing.vertices.size(), 2u);
  std::reverse(decreasing.vertices.begin(), decreasing.vertices.end());
  EXPECT_EQ(store.Put(decreasing).code(), absl::StatusCode::kInvalidArgument);

  // A tile never stored is named, and no file is left.
  const std::string path = (dir.path() / "out.exr").string();
  absl::StatusOr<std::unique_ptr<PdsmWriter>> writer = PdsmWriter::Create(path, header);
  ASSERT_TRUE(writer.ok());
  const absl::Status missing = store.WriteTo(writer->get());
  EXPECT_EQ(missing.code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_THAT(missing.message(), HasSubstr("(0, 0) was never stored"));
  writer->reset();
  EXPECT_FALSE(std::filesystem::exists(path));
}

}  // namespace
}  // namespace pdsm
