#include "core/util/atomic_file.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <string>

#include "core/util/fault_injecting_file_system.h"
#include "tests/test_support.h"
#include "tests/write_faults.h"

namespace pdsm {
namespace {

namespace fs = std::filesystem;
using ::pdsm::testing::FilesUnder;
using ::pdsm::testing::ReadBytes;
using ::pdsm::testing::TempDir;
using ::testing::ElementsAre;
using ::testing::HasSubstr;
using ::testing::IsEmpty;
using ::testing::StartsWith;

TEST(WriteFileAtomically, WritesThenReplacesLeavingNoTemporaryFile) {
  TempDir dir;
  const std::string path = dir.File("a.csv");
  ASSERT_TRUE(WriteFileAtomically(path, "one\n").ok());
  EXPECT_EQ(ReadBytes(path), "one\n");
  ASSERT_TRUE(WriteFileAtomically(path, std::string("two\0three", 9)).ok());
  EXPECT_EQ(ReadBytes(path), std::string("two\0three", 9));
  EXPECT_THAT(FilesUnder(dir.path()), ElementsAre("a.csv"));
}

TEST(WriteFileAtomically, MissingFolderIsNotFoundNamingThePath) {
  TempDir dir;
  const std::string path = dir.File("no/such/folder/a.csv");
  const absl::Status s = WriteFileAtomically(path, "x");
  EXPECT_EQ(s.code(), absl::StatusCode::kNotFound) << s;
  EXPECT_THAT(std::string(s.message()), HasSubstr(path));
  EXPECT_TRUE(fs::is_empty(dir.path()));
}

TEST(WriteFileAtomically, FailedRenameKeepsTheOldTarget) {
  TempDir dir;
  const std::string target = dir.File("target");
  fs::create_directory(target);  // a folder cannot be replaced by a file
  fs::create_directory(target + "/keep");
  const absl::Status s = WriteFileAtomically(target, "x");
  EXPECT_FALSE(s.ok());
  EXPECT_THAT(std::string(s.message()), HasSubstr(target));
  EXPECT_TRUE(fs::is_directory(target + "/keep"));
  EXPECT_EQ(std::distance(fs::directory_iterator(dir.path()), fs::directory_iterator()), 1);
}

TEST(WriteFileAtomically, EveryFailureLeavesThePreviousFile) {
  TempDir dir;
  const std::string path = dir.File("a.csv");
  ASSERT_TRUE(WriteFileAtomically(path, "the previous content\n").ok());
  testing::ExpectWriteFailuresLeaveTargetIntact(path, dir.path(), [&](FileSystem* fs) {
    return WriteFileAtomically(path, std::string(1000, 'n'), fs);
  });
}

TEST(WriteFileAtomically, EveryFailureOfAFirstWriteLeavesNothing) {
  TempDir dir;
  const std::string path = dir.File("new.bin");
  testing::ExpectWriteFailuresLeaveTargetIntact(
      path, dir.path(), [&](FileSystem* fs) { return WriteFileAtomically(path, "bytes", fs); });
}

// mkstemp creates 0600 files, which other users of a shared output folder cannot read: a new
// file gets 0666 less the umask, as any other new file.
TEST(WriteFileAtomically, NewFileHasTheUmasksMode) {
  TempDir dir;
  for (const mode_t mask : {mode_t{022}, mode_t{027}, mode_t{0}}) {
    const mode_t old_mask = ::umask(mask);
    const std::string path = dir.File("m" + std::to_string(mask));
    const absl::Status s = WriteFileAtomically(path, "x");
    ::umask(old_mask);
    ASSERT_TRUE(s.ok()) << s;
    struct stat info;
    ASSERT_EQ(::stat(path.c_str(), &info), 0);
    EXPECT_EQ(info.st_mode & 0777, 0666 & ~mask) << "umask " << mask;
  }
}

TEST(AtomicFile, StreamsAndPatchesBeforeCommit) {
  TempDir dir;
  const std::string path = dir.File("out.bin");
  absl::StatusOr<std::unique_ptr<AtomicFile>> file = AtomicFile::Create(path);
  ASSERT_TRUE(file.ok()) << file.status();
  AtomicFile& f = **file;
  EXPECT_THAT(f.temp_path(), StartsWith(path + ".tmp-"));
  EXPECT_EQ(f.temp_path().size(), path.size() + 11);  // ".tmp-" and six characters
  ASSERT_TRUE(f.Append("header??").ok());
  // Larger than the write buffer, so that the patch below lands on bytes already written.
  ASSERT_TRUE(f.Append(std::string(200000, 'd')).ok());
  ASSERT_TRUE(f.WriteAt(6, "OK").ok());
  ASSERT_TRUE(f.Append("end").ok());
  EXPECT_EQ(f.size(), 8u + 200000 + 3);
  EXPECT_FALSE(fs::exists(path)) << "visible before Commit()";
  ASSERT_TRUE(f.Flush().ok());
  EXPECT_EQ(ReadBytes(f.temp_path()).size(), f.size()) << "Flush() makes the bytes readable";
  ASSERT_TRUE(f.Commit().ok());
  const std::string bytes = ReadBytes(path);
  EXPECT_EQ(bytes.substr(0, 8), "headerOK");
  EXPECT_EQ(bytes.size(), 8u + 200000 + 3);
  EXPECT_EQ(bytes.substr(bytes.size() - 3), "end");
  EXPECT_THAT(FilesUnder(dir.path()), ElementsAre("out.bin"));
  EXPECT_EQ(f.Commit().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_EQ(f.Append("more").code(), absl::StatusCode::kFailedPrecondition);
}

TEST(AtomicFile, AbandonedFileLeavesNothing) {
  TempDir dir;
  const std::string path = dir.File("out.bin");
  ASSERT_TRUE(WriteFileAtomically(path, "old").ok());
  {
    absl::StatusOr<std::unique_ptr<AtomicFile>> file = AtomicFile::Create(path);
    ASSERT_TRUE(file.ok()) << file.status();
    ASSERT_TRUE((*file)->Append("new, never committed").ok());
    EXPECT_EQ(FilesUnder(dir.path()).size(), 2u);
  }
  EXPECT_THAT(FilesUnder(dir.path()), ElementsAre("out.bin"));
  EXPECT_EQ(ReadBytes(path), "old");
}

// Abandon() is destruction ahead of time: the temporary file goes now, and what a format
// library writes afterwards (OpenEXR's offset table, from its destructor) is refused.
TEST(AtomicFile, AbandonDropsTheFileNowAndRefusesLaterWrites) {
  TempDir dir;
  const std::string path = dir.File("out.bin");
  ASSERT_TRUE(WriteFileAtomically(path, "old").ok());
  absl::StatusOr<std::unique_ptr<AtomicFile>> file = AtomicFile::Create(path);
  ASSERT_TRUE(file.ok()) << file.status();
  ASSERT_TRUE((*file)->Append("new, never committed").ok());
  (*file)->Abandon();
  EXPECT_THAT(FilesUnder(dir.path()), ElementsAre("out.bin"));
  EXPECT_EQ((*file)->Append("trailer").code(), absl::StatusCode::kCancelled);
  EXPECT_EQ((*file)->Commit().code(), absl::StatusCode::kCancelled);
  (*file)->Abandon();  // again: nothing
  file->reset();
  EXPECT_THAT(FilesUnder(dir.path()), ElementsAre("out.bin"));
  EXPECT_EQ(ReadBytes(path), "old");
}

// The first error removes the temporary file at once (a writer that goes on failing, as
// OpenEXR's destructor does, writes nothing more) and every later call returns it.
TEST(AtomicFile, FirstErrorIsStickyAndRemovesTheTemporaryFile) {
  TempDir dir;
  const std::string path = dir.File("out.bin");
  FaultInjectingFileSystem faults;
  absl::StatusOr<std::unique_ptr<AtomicFile>> file = AtomicFile::Create(path, &faults);
  ASSERT_TRUE(file.ok()) << file.status();
  AtomicFile& f = **file;
  ASSERT_TRUE(f.Append("one").ok());
  faults.FailNth(FileOp::kWrite, 1, ENOSPC);
  const absl::Status first = f.Append("two");
  EXPECT_EQ(first.code(), absl::StatusCode::kResourceExhausted) << first;
  EXPECT_THAT(std::string(first.message()), HasSubstr(path));
  EXPECT_THAT(FilesUnder(dir.path()), IsEmpty());
  EXPECT_EQ(f.Append("three"), first);
  EXPECT_EQ(f.WriteAt(0, "x"), first);
  EXPECT_EQ(f.Flush(), first);
  EXPECT_EQ(f.Commit(), first);
  EXPECT_EQ(f.status(), first);
  EXPECT_EQ(faults.op_count(FileOp::kWrite), 2) << "nothing reaches the file after an error";
  EXPECT_FALSE(fs::exists(path));
}

TEST(FaultInjectingFileSystem, FailsOnlyTheArmedCallAndCountsEveryCall) {
  TempDir dir;
  FaultInjectingFileSystem faults;
  faults.FailNth(FileOp::kRename, 2, EACCES);
  EXPECT_TRUE(WriteFileAtomically(dir.File("a"), "1", &faults).ok());
  const absl::Status s = WriteFileAtomically(dir.File("b"), "2", &faults);
  EXPECT_EQ(s.code(), absl::StatusCode::kPermissionDenied) << s;
  EXPECT_THAT(std::string(s.message()), HasSubstr("(injected)"));
  EXPECT_TRUE(WriteFileAtomically(dir.File("c"), "3", &faults).ok()) << "fired once only";
  EXPECT_EQ(faults.op_count(FileOp::kRename), 3);
  EXPECT_EQ(faults.op_count(FileOp::kCreate), 3);
  EXPECT_EQ(faults.op_count(FileOp::kSyncDir), 2);  // none after the failed rename
  EXPECT_EQ(faults.failures(), 1);
  EXPECT_THAT(FilesUnder(dir.path()), ElementsAre("a", "c"));
}

TEST(FaultInjectingFileSystem, FullDiskWritesWhatFitsThenRefuses) {
  TempDir dir;
  FaultInjectingFileSystem faults;
  absl::StatusOr<std::unique_ptr<AtomicFile>> file = AtomicFile::Create(dir.File("a"), &faults);
  ASSERT_TRUE(file.ok()) << file.status();
  faults.SetDiskFullAfter(5);
  EXPECT_TRUE((*file)->Append("abc").ok());
  EXPECT_EQ((*file)->Append("defg").code(), absl::StatusCode::kResourceExhausted);
  EXPECT_EQ(faults.bytes_written(), 5u);
  EXPECT_EQ(faults.failures(), 1);
  faults.Reset();
  EXPECT_TRUE(WriteFileAtomically(dir.File("b"), std::string(100, 'x'), &faults).ok())
      << "Reset() frees the disk";
  EXPECT_EQ(faults.bytes_written(), 100u);
}

TEST(ErrnoStatus, MapsTheCodesWritersReport) {
  EXPECT_EQ(ErrnoStatus(ENOSPC, "w").code(), absl::StatusCode::kResourceExhausted);
  EXPECT_EQ(ErrnoStatus(ENOENT, "w").code(), absl::StatusCode::kNotFound);
  EXPECT_EQ(ErrnoStatus(EACCES, "w").code(), absl::StatusCode::kPermissionDenied);
  EXPECT_EQ(ErrnoStatus(0, "w").code(), absl::StatusCode::kUnknown);
  EXPECT_THAT(std::string(ErrnoStatus(ENOSPC, "cannot write x").message()),
              ::testing::AllOf(StartsWith("cannot write x"), HasSubstr("space")));
}

TEST(ParentDir, IsTheFolderToSync) {
  EXPECT_EQ(ParentDir("/a/b/c.exr"), "/a/b");
  EXPECT_EQ(ParentDir("c.exr"), ".");
  EXPECT_EQ(ParentDir("d/c.exr"), "d");
}

}  // namespace
}  // namespace pdsm
