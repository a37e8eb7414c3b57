#include "server/tile_log.h"

#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "core/pipeline/tile_file.h"
#include "core/util/fault_injecting_file_system.h"
#include "tests/test_support.h"

namespace pdsm {
namespace {

using testing::TempDir;

// A tile file of a 4 x 2 tile whose every pixel steps to `a` at depth 3.
std::string TileBytes(float a) {
  PdsmTile tile{.x0 = 4, .y0 = 0, .width = 4, .height = 2};
  tile.offsets.push_back(0);
  for (int p = 0; p < 8; ++p) {
    tile.vertices.push_back({3.0f, 0.0f});
    tile.vertices.push_back({3.0f, a});
    tile.offsets.push_back(tile.vertices.size());
  }
  absl::StatusOr<std::string> bytes = EncodeTileFile(tile, 4, "test tile");
  EXPECT_TRUE(bytes.ok()) << bytes.status();
  return *bytes;
}

std::unique_ptr<TileLog> OpenOrDie(const std::string& path, FileSystem* fs = nullptr) {
  absl::StatusOr<std::unique_ptr<TileLog>> log = TileLog::Open(path, fs);
  EXPECT_TRUE(log.ok()) << log.status();
  return log.ok() ? *std::move(log) : nullptr;
}

void Overwrite(const std::string& path, uint64_t offset, const std::string& bytes) {
  std::fstream file(path, std::ios::in | std::ios::out | std::ios::binary);
  file.seekp(static_cast<std::streamoff>(offset));
  file.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

TEST(TileLog, TheLastRecordOfATileIsTheTileAcrossReopens) {
  TempDir dir;
  const std::string path = dir.File("tiles.log");
  {
    std::unique_ptr<TileLog> log = OpenOrDie(path);
    ASSERT_NE(log, nullptr);
    EXPECT_TRUE(log->Tiles().empty());
    EXPECT_EQ(log->Read(7).status().code(), absl::StatusCode::kNotFound);
    ASSERT_TRUE(log->Append(7, TileBytes(0.25f)).ok());
    ASSERT_TRUE(log->Append(2, TileBytes(0.5f)).ok());
    ASSERT_TRUE(log->Append(7, TileBytes(0.75f)).ok());
    ASSERT_TRUE(log->Sync().ok());
    EXPECT_EQ(*log->Read(7), TileBytes(0.75f));
    EXPECT_EQ(log->Tiles(), (std::vector<int>{2, 7}));
    log->Forget(2);
    EXPECT_FALSE(log->Has(2));
    EXPECT_EQ(log->Read(2).status().code(), absl::StatusCode::kNotFound);
  }
  std::unique_ptr<TileLog> reopened = OpenOrDie(path);
  ASSERT_NE(reopened, nullptr);
  EXPECT_EQ(reopened->Tiles(), (std::vector<int>{2, 7}));  // forgetting is in memory only
  EXPECT_EQ(*reopened->Read(2), TileBytes(0.5f));
  EXPECT_EQ(*reopened->Read(7), TileBytes(0.75f));
}

// A crash in the middle of an append leaves part of a record at the end (or zeros where it
// was to go): reopening cuts it off, keeps every whole record, and appends after them.
TEST(TileLog, ATornOrDamagedTailIsCutOffAndAppendsGoOn) {
  TempDir dir;
  const std::string path = dir.File("tiles.log");
  uint64_t whole = 0;
  {
    std::unique_ptr<TileLog> log = OpenOrDie(path);
    ASSERT_TRUE(log->Append(1, TileBytes(0.25f)).ok());
    ASSERT_TRUE(log->Sync().ok());
    whole = std::filesystem::file_size(path);
    ASSERT_TRUE(log->Append(2, TileBytes(0.5f)).ok());
  }
  const uint64_t full = std::filesystem::file_size(path);
  struct Damage {
    const char* what;
    std::function<void()> apply;
  };
  const std::vector<Damage> damages = {
      {"cut in the frame", [&] { std::filesystem::resize_file(path, whole + 10); }},
      {"cut in the payload", [&] { std::filesystem::resize_file(path, full - 3); }},
      {"zeros for the payload",
       [&] { Overwrite(path, whole + 24, std::string(full - whole - 24, '\0')); }},
      {"a damaged frame", [&] { Overwrite(path, whole + 5, "\x7f"); }},
      {"a flipped payload byte", [&] { Overwrite(path, full - 20, "\x55"); }},
  };
  const std::string intact = testing::ReadBytes(path);
  for (const Damage& damage : damages) {
    SCOPED_TRACE(damage.what);
    testing::WriteText(path, intact);
    damage.apply();
    {
      std::unique_ptr<TileLog> log = OpenOrDie(path);
      ASSERT_NE(log, nullptr);
      EXPECT_EQ(log->Tiles(), std::vector<int>{1});
      EXPECT_EQ(std::filesystem::file_size(path), whole);
      ASSERT_TRUE(log->Append(3, TileBytes(1.0f)).ok());
    }
    std::unique_ptr<TileLog> log = OpenOrDie(path);
    EXPECT_EQ(log->Tiles(), (std::vector<int>{1, 3}));
    EXPECT_EQ(*log->Read(3), TileBytes(1.0f));
  }
}

TEST(TileLog, AFailedAppendIsCutOffAgain) {
  TempDir dir;
  const std::string path = dir.File("tiles.log");
  FaultInjectingFileSystem fs;
  std::unique_ptr<TileLog> log = OpenOrDie(path, &fs);
  ASSERT_TRUE(log->Append(1, TileBytes(0.25f)).ok());
  const std::string before = testing::ReadBytes(path);
  fs.SetDiskFullAfter(30);  // the frame fits, the payload does not
  const absl::Status full = log->Append(2, TileBytes(0.5f));
  EXPECT_EQ(full.code(), absl::StatusCode::kResourceExhausted);
  EXPECT_NE(full.message().find("tiles.log"), std::string::npos) << full;
  EXPECT_EQ(testing::ReadBytes(path), before);
  EXPECT_FALSE(log->Has(2));
  fs.Reset();
  ASSERT_TRUE(log->Append(2, TileBytes(0.5f)).ok());
  // A cut that fails too leaves the log refusing every later append and sync.
  fs.SetDiskFullAfter(30);
  fs.FailNth(FileOp::kWrite, 2);  // the append's write is the first, the cut the second
  EXPECT_FALSE(log->Append(3, TileBytes(1.0f)).ok());
  EXPECT_FALSE(log->Append(4, TileBytes(1.0f)).ok());
  EXPECT_FALSE(log->Sync().ok());
  std::unique_ptr<TileLog> reopened = OpenOrDie(path);
  EXPECT_EQ(reopened->Tiles(), (std::vector<int>{1, 2}));
}

TEST(TileLog, WhatIsNotATileLogIsRefused) {
  TempDir dir;
  const std::string other = dir.File("other.log");
  testing::WriteText(other, "a file of something else, long enough for a header");
  absl::StatusOr<std::unique_ptr<TileLog>> log = TileLog::Open(other);
  EXPECT_EQ(log.status().code(), absl::StatusCode::kDataLoss);
  EXPECT_NE(log.status().message().find("other.log"), std::string::npos) << log.status();

  const std::string newer = dir.File("newer.log");
  { OpenOrDie(newer); }
  Overwrite(newer, 8, std::string("\x09\0\0\0", 4));
  EXPECT_EQ(TileLog::Open(newer).status().code(), absl::StatusCode::kFailedPrecondition);

  EXPECT_EQ(TileLog::Open(dir.File("no/such/folder/tiles.log")).status().code(),
            absl::StatusCode::kNotFound);
}

}  // namespace
}  // namespace pdsm
