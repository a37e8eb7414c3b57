#include "core/assets/asset_store.h"

#include <filesystem>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "core/assets/mesh_asset.h"
#include "core/util/fault_injecting_file_system.h"
#include "tests/test_support.h"
#include "tests/write_faults.h"

namespace pdsm {
namespace {

using ::testing::HasSubstr;

std::string Blob(size_t size, int seed) {
  std::string bytes(size, '\0');
  for (size_t i = 0; i < size; ++i) {
    bytes[i] = static_cast<char>((i * 131 + seed * 17 + 7) & 0xff);
  }
  return bytes;
}

// The names in `dir` and its subfolders, relative to it.
std::vector<std::string> ListFiles(const std::filesystem::path& dir) {
  std::vector<std::string> names;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(dir)) {
    if (entry.is_regular_file()) names.push_back(entry.path().lexically_relative(dir).string());
  }
  return names;
}

class AssetStoreTest : public ::testing::Test {
 protected:
  void SetUp() override {
    absl::StatusOr<std::unique_ptr<AssetStore>> store = AssetStore::Open(dir_.string());
    ASSERT_TRUE(store.ok()) << store.status();
    store_ = *std::move(store);
  }

  ::pdsm::testing::TempDir temp_dir_;  // a fresh folder per test, removed after it
  const std::filesystem::path dir_ = temp_dir_.path() / "store" / "assets";
  std::unique_ptr<AssetStore> store_;
};

TEST_F(AssetStoreTest, OpenCreatesTheFolder) {
  EXPECT_TRUE(std::filesystem::is_directory(dir_));
  EXPECT_EQ(store_->dir(), dir_.string());
  // Opening an existing store is fine too.
  EXPECT_TRUE(AssetStore::Open(dir_.string()).ok());
}

TEST_F(AssetStoreTest, OpenOnAFileFails) {
  const std::string file = temp_dir_.File("plain");
  ::pdsm::testing::WriteText(file, "x");
  EXPECT_FALSE(AssetStore::Open(file).ok());
  EXPECT_FALSE(AssetStore::Open((std::filesystem::path(file) / "sub").string()).ok());
}

TEST_F(AssetStoreTest, PutGetHas) {
  const std::string bytes = Blob(10000, 1);
  const std::string sha = Sha256Hex(bytes);
  EXPECT_FALSE(store_->Has(sha));
  ASSERT_TRUE(store_->Put(sha, bytes).ok());
  EXPECT_TRUE(store_->Has(sha));
  absl::StatusOr<std::string> got = store_->Get(sha);
  ASSERT_TRUE(got.ok()) << got.status();
  EXPECT_EQ(*got, bytes);

  EXPECT_EQ(store_->PathFor(sha), (dir_ / sha.substr(0, 2) / sha).string());
  EXPECT_EQ(::pdsm::testing::ReadBytes(store_->PathFor(sha)), bytes);
  // Nothing but the blob: no temporary file left behind.
  EXPECT_THAT(ListFiles(dir_), ::testing::ElementsAre(absl::StrCat(sha.substr(0, 2), "/", sha)));
}

TEST_F(AssetStoreTest, EmptyBlob) {
  const std::string sha = Sha256Hex("");
  ASSERT_TRUE(store_->Put(sha, "").ok());
  absl::StatusOr<std::string> got = store_->Get(sha);
  ASSERT_TRUE(got.ok()) << got.status();
  EXPECT_EQ(*got, "");
}

TEST_F(AssetStoreTest, PutTwiceKeepsOneBlob) {
  const std::string bytes = Blob(100, 2);
  const std::string sha = Sha256Hex(bytes);
  ASSERT_TRUE(store_->Put(sha, bytes).ok());
  ASSERT_TRUE(store_->Put(sha, bytes).ok());
  EXPECT_EQ(store_->Get(sha).value_or("<error>"), bytes);
  EXPECT_EQ(ListFiles(dir_).size(), 1u);
}

TEST_F(AssetStoreTest, AnotherStoreOnTheSameFolderSeesTheBlobs) {
  const std::string bytes = Blob(100, 3);
  const std::string sha = Sha256Hex(bytes);
  ASSERT_TRUE(store_->Put(sha, bytes).ok());
  absl::StatusOr<std::unique_ptr<AssetStore>> other = AssetStore::Open(dir_.string());
  ASSERT_TRUE(other.ok()) << other.status();
  EXPECT_TRUE((*other)->Has(sha));
  EXPECT_EQ((*other)->Get(sha).value_or("<error>"), bytes);
}

TEST_F(AssetStoreTest, WrongHashIsRefused) {
  const std::string bytes = Blob(100, 4);
  const std::string claimed = Sha256Hex("something else");
  const absl::Status status = store_->Put(claimed, bytes);
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument) << status;
  EXPECT_EQ(status.message(),
            absl::StrCat("asset ", claimed, ": content hashes to ", Sha256Hex(bytes)));
  EXPECT_FALSE(store_->Has(claimed));
  EXPECT_TRUE(ListFiles(dir_).empty());
}

TEST_F(AssetStoreTest, MalformedHashIsRefused) {
  const std::string good = Sha256Hex("abc");
  std::string upper = good;
  upper[0] = 'B';
  for (const std::string& bad : {std::string(""), good.substr(0, 63), good + "0", upper,
                                 std::string("../../") + good.substr(6), std::string("..")}) {
    SCOPED_TRACE(bad);
    const absl::Status put = store_->Put(bad, "abc");
    EXPECT_EQ(put.code(), absl::StatusCode::kInvalidArgument) << put;
    EXPECT_THAT(put.message(), HasSubstr("not a SHA-256"));
    EXPECT_EQ(store_->Get(bad).status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_FALSE(store_->Has(bad));
  }
  EXPECT_TRUE(ListFiles(temp_dir_.path()).empty());
}

TEST_F(AssetStoreTest, MissingIsNotFound) {
  const std::string sha = Sha256Hex("never stored");
  absl::StatusOr<std::string> got = store_->Get(sha);
  EXPECT_EQ(got.status().code(), absl::StatusCode::kNotFound) << got.status();
  EXPECT_THAT(got.status().message(), HasSubstr(sha));
}

TEST_F(AssetStoreTest, CorruptFileIsDataLossAndRemoved) {
  const std::string bytes = Blob(1000, 5);
  const std::string sha = Sha256Hex(bytes);
  ASSERT_TRUE(store_->Put(sha, bytes).ok());
  std::string corrupt = bytes;
  corrupt[500] ^= 1;  // one flipped bit
  ::pdsm::testing::WriteText(store_->PathFor(sha), corrupt);

  absl::StatusOr<std::string> got = store_->Get(sha);
  EXPECT_EQ(got.status().code(), absl::StatusCode::kDataLoss) << got.status();
  EXPECT_THAT(got.status().message(), HasSubstr(sha));
  EXPECT_THAT(got.status().message(), HasSubstr(Sha256Hex(corrupt)));
  EXPECT_FALSE(store_->Has(sha));
  EXPECT_FALSE(std::filesystem::exists(store_->PathFor(sha)));
  EXPECT_EQ(store_->Get(sha).status().code(), absl::StatusCode::kNotFound);

  // A new upload repairs it.
  ASSERT_TRUE(store_->Put(sha, bytes).ok());
  EXPECT_EQ(store_->Get(sha).value_or("<error>"), bytes);
}

TEST_F(AssetStoreTest, TruncatedFileIsDataLoss) {
  const std::string bytes = Blob(1000, 6);
  const std::string sha = Sha256Hex(bytes);
  ASSERT_TRUE(store_->Put(sha, bytes).ok());
  std::filesystem::resize_file(store_->PathFor(sha), 10);
  EXPECT_EQ(store_->Get(sha).status().code(), absl::StatusCode::kDataLoss);
  EXPECT_FALSE(store_->Has(sha));
}

// A blob not stored yet, its shard folder already there: every failure of the write (each
// create, write, sync, close, rename in turn, a full disk) leaves no blob and no temporary
// file, and the blob is not reported as stored.
TEST_F(AssetStoreTest, EveryFileSystemFailureLeavesNoBlob) {
  const std::string bytes = Blob(5000, 11);
  const std::string sha = Sha256Hex(bytes);
  ASSERT_TRUE(store_->Put(sha, bytes).ok());
  std::filesystem::remove(store_->PathFor(sha));  // keeps the shard folder
  ::pdsm::testing::ExpectWriteFailuresLeaveTargetIntact(
      store_->PathFor(sha), dir_, [&](FileSystem* fs) -> absl::Status {
        absl::StatusOr<std::unique_ptr<AssetStore>> store = AssetStore::Open(dir_.string(), fs);
        if (!store.ok()) return store.status();
        absl::Status s = (*store)->Put(sha, bytes);
        if (!s.ok() && (*store)->Has(sha)) return absl::InternalError("a failed Put stored it");
        return s;
      });
  EXPECT_FALSE(store_->Has(sha));
}

// A Put that creates the blob's shard folder syncs the store's folder too, after the shard's.
TEST_F(AssetStoreTest, NewShardIsSyncedIntoTheStoreFolder) {
  FaultInjectingFileSystem faults;
  absl::StatusOr<std::unique_ptr<AssetStore>> store = AssetStore::Open(dir_.string(), &faults);
  ASSERT_TRUE(store.ok()) << store.status();
  const std::string bytes = Blob(100, 12);
  const std::string sha = Sha256Hex(bytes);
  faults.FailNth(FileOp::kSyncDir, 2, EIO);  // the store's folder, after the shard's
  const absl::Status s = (*store)->Put(sha, bytes);
  EXPECT_FALSE(s.ok());
  EXPECT_THAT(std::string(s.message()), HasSubstr(dir_.string()));
  EXPECT_EQ(faults.op_count(FileOp::kSyncDir), 2);
  // The blob itself is whole (the failure came after its rename).
  EXPECT_EQ(store_->Get(sha).value_or("<error>"), bytes);
  ASSERT_TRUE((*store)->Put(sha, bytes).ok());
  EXPECT_EQ(faults.op_count(FileOp::kSyncDir), 3) << "an existing shard: one folder sync";
  EXPECT_THAT(ListFiles(dir_), ::testing::ElementsAre(absl::StrCat(sha.substr(0, 2), "/", sha)));
}

// Several threads (standing in for processes: two store objects) uploading the same asset at
// once: every Put succeeds, the blob is whole, and no temporary file is left.
TEST_F(AssetStoreTest, ConcurrentPutsOfTheSameBlob) {
  absl::StatusOr<std::unique_ptr<AssetStore>> second = AssetStore::Open(dir_.string());
  ASSERT_TRUE(second.ok()) << second.status();
  const std::string bytes = Blob(1 << 20, 7);
  const std::string sha = Sha256Hex(bytes);
  constexpr int kThreads = 4;
  constexpr int kRounds = 5;
  std::vector<absl::Status> put_status(kThreads);
  std::vector<absl::Status> get_status(kThreads);
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t) {
    threads.emplace_back([&, t] {
      AssetStore& store = t % 2 == 0 ? *store_ : **second;
      for (int round = 0; round < kRounds; ++round) {
        absl::Status s = store.Put(sha, bytes);
        if (!s.ok() && put_status[t].ok()) put_status[t] = s;
        // Whatever the other threads are doing, a reader sees a whole blob.
        absl::StatusOr<std::string> got = store.Get(sha);
        if (got.ok() && *got != bytes) got = absl::InternalError("different bytes");
        if (!got.ok() && get_status[t].ok()) get_status[t] = got.status();
      }
    });
  }
  for (std::thread& thread : threads) thread.join();
  for (int t = 0; t < kThreads; ++t) {
    EXPECT_TRUE(put_status[t].ok()) << "thread " << t << ": " << put_status[t];
    EXPECT_TRUE(get_status[t].ok()) << "thread " << t << ": " << get_status[t];
  }
  EXPECT_EQ(store_->Get(sha).value_or("<error>"), bytes);
  EXPECT_THAT(ListFiles(dir_), ::testing::ElementsAre(absl::StrCat(sha.substr(0, 2), "/", sha)));
}

TEST_F(AssetStoreTest, ConcurrentPutsOfDifferentBlobs) {
  constexpr int kThreads = 4;
  constexpr int kBlobsPerThread = 20;
  std::vector<std::thread> threads;
  std::vector<int> failures(kThreads, 0);
  for (int t = 0; t < kThreads; ++t) {
    threads.emplace_back([&, t] {
      for (int b = 0; b < kBlobsPerThread; ++b) {
        const std::string bytes = Blob(1000 + b, 100 * t + b);
        const std::string sha = Sha256Hex(bytes);
        if (!store_->Put(sha, bytes).ok() || !store_->Has(sha) ||
            store_->Get(sha).value_or("<error>") != bytes) {
          ++failures[t];
        }
      }
    });
  }
  for (std::thread& thread : threads) thread.join();
  for (int t = 0; t < kThreads; ++t) EXPECT_EQ(failures[t], 0) << "thread " << t;
  EXPECT_EQ(ListFiles(dir_).size(), size_t{kThreads * kBlobsPerThread});
}

}  // namespace
}  // namespace pdsm
