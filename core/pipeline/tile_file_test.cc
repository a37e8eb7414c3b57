#include "core/pipeline/tile_file.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <ostream>
#include <string>
#include <vector>

#include "core/pdsm/pdsm_test_images.h"
#include "core/pdsm/tile_chunk.h"
#include "tests/test_support.h"

namespace pdsm {

namespace {

namespace fs = std::filesystem;
using ::pdsm::testing::ExpectSameTile;
using ::pdsm::testing::ReadBytes;
using ::pdsm::testing::TempDir;
using ::pdsm::testing::WriteText;
using ::testing::HasSubstr;

// Offsets of the layout (see tile_file.h).
constexpr size_t kVersionAt = 8;
constexpr size_t kChunkBytesAt = 36;
constexpr size_t kChunkAt = 44;
// The grid's tile size the tiles below are cells of.
constexpr int kTileSize = 64;
// Of versions 1 and 2.
constexpr size_t kOffsetCountAt = 28;
constexpr size_t kVertexCountAt = 36;
constexpr size_t kOffsetsAt = 44;

// A 3x2 tile at (64, 32) with empty pixels, jumps, and float values a decimal round trip
// would break.
PdsmTile SmallTile() {
  PdsmTile tile;
  tile.x0 = 64;
  tile.y0 = 32;
  tile.width = 3;
  tile.height = 2;
  tile.offsets = {0, 2, 2, 5, 6, 6, 8};
  tile.vertices = {{1.0f / 3.0f, 0.0f},
                   {2.5f, 1.0f},
                   {0.1f, 0.0f},
                   {0.1f, 0.25f},  // jump
                   {1e6f + 0.5f, 0.75f},
                   {-0.0f, std::nextafter(1.0f, 0.0f)},
                   {std::numeric_limits<float>::denorm_min(), 1.0f},
                   {3.0f, 0.5f}};
  return tile;
}

// FNV-1a 64, as the file format defines its checksum.
uint64_t Fnv1a64(const std::string& bytes) {
  uint64_t hash = 0xcbf29ce484222325ull;
  for (const char c : bytes) {
    hash ^= static_cast<unsigned char>(c);
    hash *= 0x100000001b3ull;
  }
  return hash;
}

void PutU64(std::string* bytes, size_t at, uint64_t v) {
  for (int i = 0; i < 8; ++i) (*bytes)[at + i] = static_cast<char>(v >> (8 * i));
}

// Recomputes the trailing checksum, so that a test reaches the checks behind it.
void Reseal(std::string* bytes) {
  PutU64(bytes, bytes->size() - 8, Fnv1a64(bytes->substr(0, bytes->size() - 8)));
}

// A tile file on disk, as the tests below keep them: its bytes (EncodeTileFile) written as
// they are. The coordinator keeps them in its tile log (server/tile_log.h), whose own tests
// cover durability.
absl::Status WriteTileBytes(const std::string& path, const PdsmTile& tile, int tile_size) {
  absl::StatusOr<std::string> bytes = EncodeTileFile(tile, tile_size, path);
  if (!bytes.ok()) return bytes.status();
  WriteText(path, *bytes);
  return absl::OkStatus();
}

absl::StatusOr<PdsmTile> ReadTileBytes(const std::string& path) {
  return DecodeTileFile(ReadBytes(path), path);
}

absl::StatusOr<EncodedTile> ReadChunkBytes(const std::string& path, int tile_size) {
  return DecodeTileChunkFile(ReadBytes(path), path, tile_size);
}

std::vector<std::string> FilesIn(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir)) {
    names.push_back(entry.path().filename().string());
  }
  return names;
}

TEST(TileFileTest, RoundTripIsExact) {
  TempDir dir;
  const std::string path = dir.File("tile_7.bin");
  const PdsmTile tile = SmallTile();
  ASSERT_TRUE(WriteTileBytes(path, tile, kTileSize).ok());
  absl::StatusOr<PdsmTile> read = ReadTileBytes(path);
  ASSERT_TRUE(read.ok()) << read.status();
  ExpectSameTile(*read, tile);
  // The file holds the tile as the PDSM will: its chunk, not its vertices.
  absl::StatusOr<EncodedTile> encoded = EncodeTileChunk(tile, kTileSize);
  ASSERT_TRUE(encoded.ok()) << encoded.status();
  const std::string bytes = ReadBytes(path);
  EXPECT_EQ(bytes[kVersionAt], 3);
  EXPECT_EQ(bytes.size(), kChunkAt + encoded->chunk.size() + 8u);
  EXPECT_EQ(bytes.substr(kChunkAt, encoded->chunk.size()), encoded->chunk);
  absl::StatusOr<EncodedTile> chunk = ReadChunkBytes(path, kTileSize);
  ASSERT_TRUE(chunk.ok()) << chunk.status();
  EXPECT_EQ(chunk->chunk, encoded->chunk);
  EXPECT_EQ(chunk->x0, 64);
  EXPECT_EQ(chunk->height, 2);
}

TEST(TileFileTest, AdaptiveTileKeepsItsSampleCount) {
  TempDir dir;
  PdsmTile tile = SmallTile();
  tile.samples = 48;
  ASSERT_TRUE(WriteTileBytes(dir.File("a"), tile, kTileSize).ok());
  absl::StatusOr<PdsmTile> read = ReadTileBytes(dir.File("a"));
  ASSERT_TRUE(read.ok()) << read.status();
  ExpectSameTile(*read, tile);
  EXPECT_EQ(read->samples, 48);
  EXPECT_EQ(ReadChunkBytes(dir.File("a"), kTileSize)->samples, 48);
  tile.samples = 0;
  ASSERT_TRUE(WriteTileBytes(dir.File("f"), tile, kTileSize).ok());
  EXPECT_EQ(ReadTileBytes(dir.File("f"))->samples, 0);
}

// Files of earlier builds (versions 1 and 2: the vertices themselves) are still read, so a job
// survives an upgrade of its coordinator; their chunk is made when the file is assembled.
TEST(TileFileTest, EarlierVersionsAreStillRead) {
  TempDir dir;
  for (const int samples : {0, 48}) {
    PdsmTile tile = SmallTile();
    tile.samples = samples;
    const std::string bytes = EncodeEarlierTileFile(tile);
    EXPECT_EQ(bytes[kVersionAt], samples == 0 ? 1 : 2);
    EXPECT_EQ(bytes.size(), 44 + 7 * 8 + 8 * 8 + (samples == 0 ? 0 : 4) + 8u);
    WriteText(dir.File("old"), bytes);
    absl::StatusOr<PdsmTile> read = ReadTileBytes(dir.File("old"));
    ASSERT_TRUE(read.ok()) << read.status();
    ExpectSameTile(*read, tile);
    absl::StatusOr<EncodedTile> chunk = ReadChunkBytes(dir.File("old"), kTileSize);
    ASSERT_TRUE(chunk.ok()) << chunk.status();
    EXPECT_EQ(chunk->chunk, EncodeTileChunk(tile, kTileSize)->chunk);
    EXPECT_EQ(chunk->samples, samples);
    for (size_t cut = 1; cut < 12; ++cut) {
      WriteText(dir.File("cut"), bytes.substr(0, bytes.size() - cut));
      EXPECT_EQ(ReadTileBytes(dir.File("cut")).status().code(), absl::StatusCode::kDataLoss);
    }
  }
}

TEST(TileFileTest, RoundTripOfTileWithoutVertices) {
  TempDir dir;
  PdsmTile tile;
  tile.x0 = 128;
  tile.y0 = 0;
  tile.width = 4;
  tile.height = 3;
  tile.offsets.assign(13, 0);
  ASSERT_TRUE(WriteTileBytes(dir.File("empty"), tile, kTileSize).ok());
  absl::StatusOr<PdsmTile> read = ReadTileBytes(dir.File("empty"));
  ASSERT_TRUE(read.ok()) << read.status();
  ExpectSameTile(*read, tile);
  EXPECT_TRUE(read->vertices.empty());
}

TEST(TileFileTest, RoundTripOfZeroPixelTile) {
  TempDir dir;
  PdsmTile tile;
  tile.offsets = {0};
  ASSERT_TRUE(WriteTileBytes(dir.File("zero"), tile, kTileSize).ok());
  absl::StatusOr<PdsmTile> read = ReadTileBytes(dir.File("zero"));
  ASSERT_TRUE(read.ok()) << read.status();
  ExpectSameTile(*read, tile);
}

TEST(TileFileTest, RoundTripOfLargerTile) {
  TempDir dir;
  PdsmTile tile;
  tile.x0 = 0;
  tile.y0 = 64;
  tile.width = 64;
  tile.height = 64;
  tile.offsets.push_back(0);
  for (int p = 0; p < 64 * 64; ++p) {
    for (int k = 0; k < p % 5; ++k) {
      tile.vertices.push_back({static_cast<float>(p) + 0.125f * k, 0.2f * k});
    }
    tile.offsets.push_back(tile.vertices.size());
  }
  ASSERT_TRUE(WriteTileBytes(dir.File("big"), tile, kTileSize).ok());
  absl::StatusOr<PdsmTile> read = ReadTileBytes(dir.File("big"));
  ASSERT_TRUE(read.ok()) << read.status();
  ExpectSameTile(*read, tile);
}

TEST(TileFileTest, RejectsInconsistentTileOnWrite) {
  TempDir dir;
  const std::string path = dir.File("tile");
  PdsmTile wrong_count = SmallTile();
  wrong_count.offsets.pop_back();
  PdsmTile not_spanning = SmallTile();
  not_spanning.vertices.pop_back();
  PdsmTile decreasing = SmallTile();
  decreasing.offsets[2] = 1;
  PdsmTile negative = SmallTile();
  negative.width = -3;
  for (const PdsmTile& tile : {wrong_count, not_spanning, decreasing, negative}) {
    EXPECT_EQ(WriteTileBytes(path, tile, kTileSize).code(), absl::StatusCode::kInvalidArgument);
  }
  EXPECT_TRUE(FilesIn(dir.path()).empty());
}

TEST(TileFileTest, TruncationAtEveryByteIsDataLoss) {
  TempDir dir;
  const std::string good = dir.File("good");
  ASSERT_TRUE(WriteTileBytes(good, SmallTile(), kTileSize).ok());
  const std::string bytes = ReadBytes(good);
  const std::string path = dir.File("cut");
  for (size_t n = 0; n < bytes.size(); ++n) {
    WriteText(path, bytes.substr(0, n));
    absl::StatusOr<PdsmTile> read = ReadTileBytes(path);
    EXPECT_EQ(read.status().code(), absl::StatusCode::kDataLoss) << n << " bytes";
    EXPECT_THAT(read.status().message(), HasSubstr(path)) << n << " bytes";
  }
}

TEST(TileFileTest, TrailingBytesAreDataLoss) {
  TempDir dir;
  const std::string path = dir.File("tile");
  ASSERT_TRUE(WriteTileBytes(path, SmallTile(), kTileSize).ok());
  WriteText(path, ReadBytes(path) + std::string(8, '\0'));
  EXPECT_EQ(ReadTileBytes(path).status().code(), absl::StatusCode::kDataLoss);
}

TEST(TileFileTest, FlippedBitAnywhereIsDataLoss) {
  TempDir dir;
  const std::string good = dir.File("good");
  ASSERT_TRUE(WriteTileBytes(good, SmallTile(), kTileSize).ok());
  const std::string bytes = ReadBytes(good);
  const std::string path = dir.File("flipped");
  for (size_t i = 0; i < bytes.size(); ++i) {
    for (const int bit : {0, 7}) {
      std::string corrupt = bytes;
      corrupt[i] = static_cast<char>(corrupt[i] ^ (1 << bit));
      WriteText(path, corrupt);
      absl::StatusOr<PdsmTile> read = ReadTileBytes(path);
      EXPECT_EQ(read.status().code(), absl::StatusCode::kDataLoss) << "byte " << i;
      EXPECT_THAT(read.status().message(), HasSubstr(path)) << "byte " << i;
    }
  }
}

TEST(TileFileTest, ChecksumMismatchIsNamed) {
  TempDir dir;
  const std::string path = dir.File("tile");
  ASSERT_TRUE(WriteTileBytes(path, SmallTile(), kTileSize).ok());
  std::string bytes = ReadBytes(path);
  bytes[kChunkAt + 20] ^= 0x10;  // in the chunk
  WriteText(path, bytes);
  EXPECT_THAT(ReadTileBytes(path).status().message(), HasSubstr("checksum"));
}

TEST(TileFileTest, NotATileFile) {
  TempDir dir;
  const std::string path = dir.File("tile");
  WriteText(path, std::string(200, 'x'));
  absl::StatusOr<PdsmTile> read = ReadTileBytes(path);
  EXPECT_EQ(read.status().code(), absl::StatusCode::kDataLoss);
  EXPECT_THAT(read.status().message(), HasSubstr("magic"));
}

// A header claiming huge sizes under a valid checksum: rejected against the file's length,
// without trying to allocate what it claims.
TEST(TileFileTest, HugeSizesUnderValidChecksumAreDataLoss) {
  TempDir dir;
  const std::string good = dir.File("good");
  ASSERT_TRUE(WriteTileBytes(good, SmallTile(), kTileSize).ok());
  const std::string path = dir.File("huge");
  for (const uint64_t count : {uint64_t{1} << 40, uint64_t{1} << 61, ~uint64_t{0}}) {
    std::string bytes = ReadBytes(good);
    PutU64(&bytes, kChunkBytesAt, count);
    Reseal(&bytes);
    WriteText(path, bytes);
    EXPECT_EQ(ReadTileBytes(path).status().code(), absl::StatusCode::kDataLoss) << count;

    bytes = EncodeEarlierTileFile(SmallTile());
    PutU64(&bytes, kVertexCountAt, count);
    Reseal(&bytes);
    WriteText(path, bytes);
    EXPECT_EQ(ReadTileBytes(path).status().code(), absl::StatusCode::kDataLoss) << count;

    bytes = EncodeEarlierTileFile(SmallTile());
    PutU64(&bytes, kOffsetCountAt, count);
    Reseal(&bytes);
    WriteText(path, bytes);
    EXPECT_EQ(ReadTileBytes(path).status().code(), absl::StatusCode::kDataLoss) << count;
  }
  // Width and height as large as int32 allows.
  for (std::string bytes : {ReadBytes(good), EncodeEarlierTileFile(SmallTile())}) {
    for (size_t at : {20, 24}) {
      for (int i = 0; i < 4; ++i) bytes[at + i] = static_cast<char>(i == 3 ? 0x7f : 0xff);
    }
    Reseal(&bytes);
    WriteText(path, bytes);
    EXPECT_EQ(ReadTileBytes(path).status().code(), absl::StatusCode::kDataLoss);
  }
}

TEST(TileFileTest, BadOffsetsOfAnEarlierVersionUnderValidChecksumAreDataLoss) {
  TempDir dir;
  const std::string path = dir.File("bad");
  struct Case {
    size_t index;
    uint64_t value;
    const char* message;
  };
  for (const Case& c :
       {Case{2, 1, "decrease"}, Case{0, 1, "first offset"}, Case{6, 7, "last offset"}}) {
    std::string bytes = EncodeEarlierTileFile(SmallTile());
    PutU64(&bytes, kOffsetsAt + 8 * c.index, c.value);
    Reseal(&bytes);
    WriteText(path, bytes);
    absl::StatusOr<PdsmTile> read = ReadTileBytes(path);
    EXPECT_EQ(read.status().code(), absl::StatusCode::kDataLoss) << c.message;
    EXPECT_THAT(read.status().message(), HasSubstr(c.message));
  }
}

TEST(TileFileTest, NewerVersionIsFailedPrecondition) {
  TempDir dir;
  const std::string path = dir.File("tile");
  ASSERT_TRUE(WriteTileBytes(path, SmallTile(), kTileSize).ok());
  std::string bytes = ReadBytes(path);
  bytes[kVersionAt] = static_cast<char>(kTileFileVersion + 1);
  Reseal(&bytes);
  WriteText(path, bytes);
  EXPECT_EQ(ReadTileBytes(path).status().code(), absl::StatusCode::kFailedPrecondition);
}

}  // namespace
}  // namespace pdsm
