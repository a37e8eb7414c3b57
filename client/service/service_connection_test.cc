// ReceivePdsm, DownloadPdsm's writing half, from a scripted FetchPdsm stream: the fetched
// file appears whole or not at all.
#include "client/service/service_connection.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "core/util/fault_injecting_file_system.h"
#include "tests/test_support.h"
#include "tests/write_faults.h"

namespace pdsm {
namespace {

using ::testing::HasSubstr;

// Yields `chunks` (each announcing `total` bytes), then finishes with `status`.
class ScriptedStream final : public grpc::ClientReaderInterface<pdsm::v1::PdsmChunk> {
 public:
  ScriptedStream(std::vector<std::string> chunks, uint64_t total, grpc::Status status)
      : chunks_(std::move(chunks)), total_(total), status_(std::move(status)) {}

  bool Read(pdsm::v1::PdsmChunk* chunk) override {
    if (next_ == chunks_.size()) return false;
    chunk->set_total_bytes(total_);
    chunk->set_data(chunks_[next_++]);
    return true;
  }
  grpc::Status Finish() override { return status_; }
  bool NextMessageSize(uint32_t* size) override {
    if (next_ == chunks_.size()) return false;
    *size = static_cast<uint32_t>(chunks_[next_].size());
    return true;
  }
  void WaitForInitialMetadata() override {}

  size_t chunks_read() const { return next_; }

 private:
  std::vector<std::string> chunks_;
  uint64_t total_;
  grpc::Status status_;
  size_t next_ = 0;
};

std::vector<std::string> Chunks() { return {std::string(70000, 'a'), "bc", std::string(9, 'd')}; }
constexpr uint64_t kTotal = 70000 + 2 + 9;

TEST(ReceivePdsm, WritesEveryChunk) {
  testing::TempDir dir;
  ScriptedStream stream(Chunks(), kTotal, grpc::Status::OK);
  grpc::ClientContext context;
  absl::StatusOr<uint64_t> received =
      ReceivePdsm(&context, &stream, "job1", "host:1", dir.File("out.exr"));
  ASSERT_TRUE(received.ok()) << received.status();
  EXPECT_EQ(*received, kTotal);
  EXPECT_EQ(testing::ReadBytes(dir.File("out.exr")), Chunks()[0] + Chunks()[1] + Chunks()[2]);
  EXPECT_THAT(testing::FilesUnder(dir.path()), ::testing::ElementsAre("out.exr"));
}

TEST(ReceivePdsm, EveryFileSystemFailureLeavesThePreviousFile) {
  testing::TempDir dir;
  const std::string path = dir.File("out.exr");
  testing::WriteText(path, "an earlier fetch");
  testing::ExpectWriteFailuresLeaveTargetIntact(path, dir.path(), [&](FileSystem* fs) {
    ScriptedStream stream(Chunks(), kTotal, grpc::Status::OK);
    grpc::ClientContext context;
    return ReceivePdsm(&context, &stream, "job1", "host:1", path, fs).status();
  });
}

// The stream ends short, or with an error: nothing is committed.
TEST(ReceivePdsm, IncompleteOrFailedStreamLeavesThePreviousFile) {
  testing::TempDir dir;
  const std::string path = dir.File("out.exr");
  testing::WriteText(path, "an earlier fetch");
  {
    ScriptedStream stream(Chunks(), kTotal + 1, grpc::Status::OK);
    grpc::ClientContext context;
    const absl::Status s = ReceivePdsm(&context, &stream, "job1", "host:1", path).status();
    EXPECT_EQ(s.code(), absl::StatusCode::kDataLoss) << s;
    EXPECT_THAT(std::string(s.message()), HasSubstr("got 70011 of 70012 bytes"));
  }
  {
    ScriptedStream stream(Chunks(), kTotal,
                          grpc::Status(grpc::StatusCode::UNAVAILABLE, "connection lost"));
    grpc::ClientContext context;
    const absl::Status s = ReceivePdsm(&context, &stream, "job1", "host:1", path).status();
    EXPECT_EQ(s.code(), absl::StatusCode::kUnavailable) << s;
    EXPECT_THAT(std::string(s.message()), HasSubstr("host:1"));
  }
  EXPECT_EQ(testing::ReadBytes(path), "an earlier fetch");
  EXPECT_THAT(testing::FilesUnder(dir.path()), ::testing::ElementsAre("out.exr"));
}

// A full disk stops the download at once (the call is cancelled), not after the last chunk.
TEST(ReceivePdsm, WriteFailureStopsReading) {
  testing::TempDir dir;
  FaultInjectingFileSystem faults;
  faults.SetDiskFullAfter(100);
  ScriptedStream stream(Chunks(), kTotal, grpc::Status::OK);
  grpc::ClientContext context;
  const absl::Status s =
      ReceivePdsm(&context, &stream, "job1", "host:1", dir.File("out.exr"), &faults).status();
  EXPECT_EQ(s.code(), absl::StatusCode::kResourceExhausted) << s;
  EXPECT_EQ(stream.chunks_read(), 1u);
  EXPECT_TRUE(std::filesystem::is_empty(dir.path()));
}

}  // namespace
}  // namespace pdsm
