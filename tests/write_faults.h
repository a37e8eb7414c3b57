// One check for every writer of the project: each failure the FaultInjectingFileSystem can
// inject (every call of every step in turn, a full disk at several points, a failed folder
// sync) leaves the target byte-identical to what it was and no temporary file beside it, and
// the error names the target.
#ifndef PDSM_TESTS_WRITE_FAULTS_H_
#define PDSM_TESTS_WRITE_FAULTS_H_

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cerrno>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <set>
#include <string>

#include "absl/status/status.h"
#include "core/util/fault_injecting_file_system.h"
#include "tests/test_support.h"

namespace pdsm::testing {

// Writes the file under test through `fs`.
using FileWriter = std::function<absl::Status(FileSystem* fs)>;

// The regular files under `dir`, as paths relative to it.
inline std::set<std::string> FilesUnder(const std::filesystem::path& dir) {
  std::set<std::string> files;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(dir)) {
    if (entry.is_regular_file()) {
      files.insert(std::filesystem::relative(entry.path(), dir).string());
    }
  }
  return files;
}

// The file's bytes, or nullopt when there is none.
inline std::optional<std::string> ContentOf(const std::string& path) {
  if (!std::filesystem::exists(path)) return std::nullopt;
  return ReadBytes(path);
}

// Puts `path` back as `content` says (absent for nullopt).
inline void Restore(const std::string& path, const std::optional<std::string>& content) {
  if (content) {
    WriteText(path, *content);
  } else {
    std::filesystem::remove(path);
  }
}

// REQUIRES: `write` replaces `target` (which may not exist yet) with content that differs
// from its current one, the same way each time it is called, and writes nothing else under
// `dir`, the folder to watch for leftovers (the target's, or one above it).
inline void ExpectWriteFailuresLeaveTargetIntact(const std::string& target,
                                                 const std::filesystem::path& dir,
                                                 const FileWriter& write) {
  const std::optional<std::string> old_content = ContentOf(target);
  const std::set<std::string> old_files = FilesUnder(dir);

  // A clean run counts the calls that the failing runs break one by one.
  FaultInjectingFileSystem fs;
  ASSERT_TRUE(write(&fs).ok()) << "the writer fails without any fault";
  const std::optional<std::string> new_content = ContentOf(target);
  ASSERT_TRUE(new_content.has_value());
  ASSERT_NE(new_content, old_content) << "the writer must change " << target;
  std::set<std::string> new_files = old_files;
  new_files.insert(std::filesystem::relative(target, dir).string());
  ASSERT_EQ(FilesUnder(dir), new_files);
  const uint64_t bytes = fs.bytes_written();
  std::map<FileOp, int> calls;
  for (FileOp op : {FileOp::kCreate, FileOp::kWrite, FileOp::kFlush, FileOp::kSync, FileOp::kClose,
                    FileOp::kRename, FileOp::kSyncDir}) {
    calls[op] = fs.op_count(op);
  }
  EXPECT_GE(calls[FileOp::kSync], 1) << "data never synced";
  EXPECT_GE(calls[FileOp::kRename], 1);
  EXPECT_GE(calls[FileOp::kSyncDir], 1) << "the rename is not made durable";
  Restore(target, old_content);

  const auto expect_intact = [&](const absl::Status& s, absl::StatusCode code) {
    EXPECT_FALSE(s.ok());
    EXPECT_EQ(s.code(), code) << s;
    EXPECT_THAT(std::string(s.message()), ::testing::HasSubstr(target));
    EXPECT_EQ(fs.failures(), 1) << "the fault did not fire (or fired twice)";
    EXPECT_EQ(ContentOf(target), old_content) << "the previous file changed";
    EXPECT_EQ(FilesUnder(dir), old_files) << "something was left behind";
  };
  for (const auto& [op, count] : calls) {
    if (op == FileOp::kSyncDir) continue;  // after the rename: below
    for (int n = 1; n <= count; ++n) {
      SCOPED_TRACE(std::string("failing ") + FileOpName(op) + " call " + std::to_string(n));
      fs.Reset();
      fs.FailNth(op, n, EIO);
      expect_intact(write(&fs), absl::ErrnoToStatusCode(EIO));
    }
  }
  for (const uint64_t limit : {uint64_t{0}, uint64_t{1}, bytes / 2, bytes - 1}) {
    SCOPED_TRACE("disk full after " + std::to_string(limit) + " of " + std::to_string(bytes) +
                 " bytes");
    fs.Reset();
    fs.SetDiskFullAfter(limit);
    expect_intact(write(&fs), absl::StatusCode::kResourceExhausted);
  }
  // A folder sync fails after the rename: the target is then whole and new, never a mix,
  // and still no temporary file is left.
  for (int n = 1; n <= calls[FileOp::kSyncDir]; ++n) {
    SCOPED_TRACE("failing folder sync call " + std::to_string(n));
    fs.Reset();
    fs.FailNth(FileOp::kSyncDir, n, EIO);
    const absl::Status s = write(&fs);
    EXPECT_FALSE(s.ok());
    EXPECT_EQ(fs.failures(), 1);
    EXPECT_EQ(ContentOf(target), new_content);
    EXPECT_EQ(FilesUnder(dir), new_files);
    Restore(target, old_content);
  }
}

}  // namespace pdsm::testing

#endif  // PDSM_TESTS_WRITE_FAULTS_H_
