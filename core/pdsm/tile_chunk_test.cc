#include "core/pdsm/tile_chunk.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "absl/strings/str_format.h"
#include "core/pdsm/pdsm_file.h"
#include "core/pdsm/pdsm_test_images.h"
#include "tests/test_support.h"

namespace pdsm {
namespace {

using ::pdsm::testing::CutTiles;
using ::pdsm::testing::ExpectSameTile;
using ::pdsm::testing::FullHeader;
using ::pdsm::testing::RandomImage;
using ::pdsm::testing::ReadBytes;
using ::pdsm::testing::RefineSomePixels;
using ::pdsm::testing::TempDir;
using ::pdsm::testing::WriteTiles;
using ::testing::HasSubstr;

std::vector<EncodedTile> EncodeAll(const std::vector<PdsmTile>& tiles, int tile_size) {
  std::vector<EncodedTile> encoded;
  for (const PdsmTile& tile : tiles) {
    absl::StatusOr<EncodedTile> e = EncodeTileChunk(tile, tile_size);
    EXPECT_TRUE(e.ok()) << e.status();
    encoded.push_back(e.ok() ? *e : EncodedTile{});
  }
  return encoded;
}

// Writes `tiles` (each the grid cell of its index) through WriteEncodedTiles.
absl::Status WriteEncoded(const std::string& path, const PdsmHeader& header,
                          const std::vector<EncodedTile>& tiles) {
  absl::StatusOr<std::unique_ptr<PdsmWriter>> writer = PdsmWriter::Create(path, header);
  if (!writer.ok()) return writer.status();
  if (absl::Status s = (*writer)->WriteEncodedTiles(
          [&](int64_t index) -> absl::StatusOr<EncodedTile> { return tiles.at(index); });
      !s.ok()) {
    return s;
  }
  return (*writer)->Finish();
}

TEST(PdsmTileChunkTest, EveryTileComesBackExactly) {
  // Edge tiles of 37 x 21 in tiles of 16 are 5 and 5 wide: every shape a grid cuts.
  const PdsmImage image = RandomImage(FullHeader(37, 21, 16), 7, /*big_count=*/300);
  for (const PdsmTile& tile : CutTiles(image)) {
    absl::StatusOr<EncodedTile> encoded = EncodeTileChunk(tile, 16);
    ASSERT_TRUE(encoded.ok()) << encoded.status();
    EXPECT_EQ(encoded->x0, tile.x0);
    EXPECT_EQ(encoded->width, tile.width);
    absl::StatusOr<PdsmTile> decoded = DecodeTileChunk(*encoded, "test");
    ASSERT_TRUE(decoded.ok()) << decoded.status();
    ExpectSameTile(*decoded, tile);
  }
}

TEST(PdsmTileChunkTest, RefinedPixelsComeBackExactly) {
  PdsmImage image = RandomImage(FullHeader(37, 21, 16), 8);
  image.header.max_refinement = 8;
  RefineSomePixels(&image, 9, /*every=*/3);
  for (const PdsmTile& tile : CutTiles(image)) {
    absl::StatusOr<EncodedTile> encoded = EncodeTileChunk(tile, 16);
    ASSERT_TRUE(encoded.ok()) << encoded.status();
    absl::StatusOr<PdsmTile> decoded = DecodeTileChunk(*encoded, "test");
    ASSERT_TRUE(decoded.ok()) << decoded.status();
    ExpectSameTile(*decoded, tile);
  }
}

TEST(PdsmTileChunkTest, TilesWithoutVerticesAndWithoutPixels) {
  PdsmTile lit;
  lit.x0 = 32;
  lit.width = 16;
  lit.height = 3;
  lit.samples = 12;
  lit.offsets.assign(16 * 3 + 1, 0);
  absl::StatusOr<EncodedTile> encoded = EncodeTileChunk(lit, 16);
  ASSERT_TRUE(encoded.ok()) << encoded.status();
  EXPECT_FALSE(encoded->chunk.empty());
  EXPECT_EQ(encoded->samples, 12);
  absl::StatusOr<PdsmTile> decoded = DecodeTileChunk(*encoded, "test");
  ASSERT_TRUE(decoded.ok()) << decoded.status();
  ExpectSameTile(*decoded, lit);

  PdsmTile none;
  none.offsets = {0};
  encoded = EncodeTileChunk(none, 16);
  ASSERT_TRUE(encoded.ok()) << encoded.status();
  EXPECT_TRUE(encoded->chunk.empty());
  decoded = DecodeTileChunk(*encoded, "test");
  ASSERT_TRUE(decoded.ok()) << decoded.status();
  ExpectSameTile(*decoded, none);
}

TEST(PdsmTileChunkTest, RefusesWhatAPdsmCannotHold) {
  PdsmTile tile;
  tile.width = 2;
  tile.height = 1;
  tile.offsets = {0, 2, 3};
  tile.vertices = {{2.0f, 0.5f}, {1.0f, 1.0f}, {1.0f, 0.0f}};  // depths decrease
  EXPECT_EQ(EncodeTileChunk(tile, 16).status().code(), absl::StatusCode::kInvalidArgument);
  tile.offsets = {0, 2};
  EXPECT_EQ(EncodeTileChunk(tile, 16).status().code(), absl::StatusCode::kInvalidArgument);
}

TEST(PdsmTileChunkTest, ACorruptChunkIsDataLossNamingIt) {
  const PdsmImage image = RandomImage(FullHeader(16, 16, 16), 3);
  absl::StatusOr<EncodedTile> encoded = EncodeTileChunk(CutTiles(image).front(), 16);
  ASSERT_TRUE(encoded.ok()) << encoded.status();
  std::mt19937 rng(5);
  int refused = 0;
  for (int trial = 0; trial < 200; ++trial) {
    EncodedTile bad = *encoded;
    const size_t at = std::uniform_int_distribution<size_t>(16, bad.chunk.size() - 1)(rng);
    bad.chunk[at] = static_cast<char>(bad.chunk[at] ^ (1 << (trial % 8)));
    if (trial % 4 == 0) bad.chunk.resize(at);  // truncated too
    absl::StatusOr<PdsmTile> decoded = DecodeTileChunk(bad, "tile 7");
    // zlib's checks do not see every flip; what is not refused is still a tile a PDSM holds.
    if (!decoded.ok()) {
      ++refused;
      EXPECT_EQ(decoded.status().code(), absl::StatusCode::kDataLoss);
      EXPECT_THAT(decoded.status().message(), HasSubstr("tile 7"));
    }
  }
  EXPECT_GT(refused, 100);
  EncodedTile huge = *encoded;
  huge.width = huge.height = 1 << 20;  // no allocation of 2^40 counts
  EXPECT_EQ(DecodeTileChunk(huge, "tile 7").status().code(), absl::StatusCode::kDataLoss);
}

// The whole point: a file written from encoded tiles is the file WriteTile writes.
TEST(PdsmTileChunkTest, EncodedTilesMakeTheSameFileAsTiles) {
  TempDir dir;
  const PdsmHeader header = FullHeader(70, 45, 16);
  const PdsmImage image = RandomImage(header, 11, /*big_count=*/5000);
  std::vector<PdsmTile> tiles = CutTiles(image);
  const std::string direct = (dir.path() / "direct.exr").string();
  const std::string copied = (dir.path() / "copied.exr").string();
  ASSERT_TRUE(WriteTiles(direct, header, tiles).ok());
  ASSERT_TRUE(WriteEncoded(copied, header, EncodeAll(tiles, header.tile_size)).ok());
  EXPECT_EQ(ReadBytes(copied), ReadBytes(direct));
}

TEST(PdsmTileChunkTest, EncodedTilesMakeTheSameFileAtEverySmallSize) {
  TempDir dir;
  struct Size {
    int width, height, tile;
  };
  for (const Size& size : {Size{1, 1, 16}, Size{1, 1, 1}, Size{1, 5, 4}, Size{17, 1, 16},
                           Size{2, 2, 64}, Size{16, 16, 16}, Size{33, 2, 8}}) {
    SCOPED_TRACE(absl::StrFormat("%dx%d in tiles of %d", size.width, size.height, size.tile));
    const PdsmHeader header = FullHeader(size.width, size.height, size.tile);
    const std::vector<PdsmTile> tiles =
        CutTiles(RandomImage(header, 3 + static_cast<uint32_t>(size.width)));
    const std::string direct = (dir.path() / "direct.exr").string();
    const std::string copied = (dir.path() / "copied.exr").string();
    ASSERT_TRUE(WriteTiles(direct, header, tiles).ok());
    ASSERT_TRUE(WriteEncoded(copied, header, EncodeAll(tiles, header.tile_size)).ok());
    EXPECT_EQ(ReadBytes(copied), ReadBytes(direct));
  }
}

TEST(PdsmTileChunkTest, EncodedTilesMakeTheSameAdaptiveFile) {
  TempDir dir;
  PdsmHeader header = FullHeader(40, 33, 16);
  header.samples = 64;
  header.adaptive_tolerance = 0.05;
  header.adaptive_min_samples = 8;
  const PdsmImage image = RandomImage(header, 13);
  std::vector<PdsmTile> tiles = CutTiles(image);
  for (size_t i = 0; i < tiles.size(); ++i) tiles[i].samples = 8 + static_cast<int>(i) * 7;
  const std::string direct = (dir.path() / "direct.exr").string();
  const std::string copied = (dir.path() / "copied.exr").string();
  ASSERT_TRUE(WriteTiles(direct, header, tiles).ok());
  ASSERT_TRUE(WriteEncoded(copied, header, EncodeAll(tiles, header.tile_size)).ok());
  EXPECT_EQ(ReadBytes(copied), ReadBytes(direct));
}

TEST(PdsmTileChunkTest, EncodedTilesMakeTheSameMultipartFile) {
  TempDir dir;
  std::vector<PdsmHeader> headers = {FullHeader(48, 20, 16), FullHeader(30, 37, 8)};
  headers[0].light_name = "sun";
  headers[1].light_name = "lamp";
  const auto write = [&](const std::string& path, bool encoded) {
    absl::StatusOr<std::unique_ptr<PdsmLightsWriter>> writer =
        PdsmLightsWriter::Create(path, 2, 48, 37);
    ASSERT_TRUE(writer.ok()) << writer.status();
    for (size_t l = 0; l < headers.size(); ++l) {
      absl::StatusOr<PdsmWriter*> part = (*writer)->BeginLight(headers[l]);
      ASSERT_TRUE(part.ok()) << part.status();
      const std::vector<PdsmTile> tiles =
          CutTiles(RandomImage(headers[l], 20 + static_cast<uint32_t>(l)));
      if (encoded) {
        const std::vector<EncodedTile> chunks = EncodeAll(tiles, headers[l].tile_size);
        ASSERT_TRUE((*part)
                        ->WriteEncodedTiles([&](int64_t index) -> absl::StatusOr<EncodedTile> {
                          return chunks.at(index);
                        })
                        .ok());
      } else {
        for (const PdsmTile& tile : tiles) ASSERT_TRUE((*part)->WriteTile(tile).ok());
      }
      ASSERT_TRUE((*part)->Finish().ok());
    }
    ASSERT_TRUE((*writer)->Finish().ok());
  };
  write((dir.path() / "direct.exr").string(), false);
  write((dir.path() / "copied.exr").string(), true);
  EXPECT_EQ(ReadBytes((dir.path() / "copied.exr").string()),
            ReadBytes((dir.path() / "direct.exr").string()));
}

TEST(PdsmTileChunkTest, ASourceErrorOrAMisplacedTileLeavesNoFile) {
  TempDir dir;
  const PdsmHeader header = FullHeader(40, 40, 16);
  const std::vector<EncodedTile> tiles =
      EncodeAll(CutTiles(RandomImage(header, 17)), header.tile_size);
  const std::string path = (dir.path() / "out.exr").string();
  absl::StatusOr<std::unique_ptr<PdsmWriter>> writer = PdsmWriter::Create(path, header);
  ASSERT_TRUE(writer.ok());
  const absl::Status failed =
      (*writer)->WriteEncodedTiles([&](int64_t index) -> absl::StatusOr<EncodedTile> {
        if (index == 5) return absl::NotFoundError("tile 5 is gone");
        return tiles.at(index);
      });
  EXPECT_EQ(failed, absl::NotFoundError("tile 5 is gone"));
  EXPECT_EQ((*writer)->Finish(), failed);  // sticky
  writer->reset();

  writer = PdsmWriter::Create(path, header);
  ASSERT_TRUE(writer.ok());
  const absl::Status misplaced =
      (*writer)->WriteEncodedTiles([&](int64_t index) -> absl::StatusOr<EncodedTile> {
        return tiles.at(index == 3 ? 4 : index);
      });
  EXPECT_EQ(misplaced.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(misplaced.message(), HasSubstr("not the grid's cell"));
  writer->reset();
  EXPECT_TRUE(std::filesystem::is_empty(dir.path()));
}

}  // namespace
}  // namespace pdsm
