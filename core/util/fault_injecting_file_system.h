// A FileSystem test double that breaks on purpose: the Nth create, write, flush, sync,
// close, rename or folder sync fails with a chosen errno, or the disk fills up after K bytes.
// Everything else is forwarded to a real FileSystem, so the files are real and a test reads
// them back. For tests; compiled into pdsm_core so that every test binary can use it.
//
//   FaultInjectingFileSystem fs;
//   fs.FailNth(FileOp::kRename, 1);              // the next rename fails with EIO
//   EXPECT_FALSE(WriteFileAtomically(path, bytes, &fs).ok());
//   // `path` still holds its previous bytes; no "<path>.tmp-*" is left.
//
// Tests that sweep every call first run the write once and read op_count(), then fail
// calls 1 .. op_count() in turn.
#ifndef PDSM_CORE_UTIL_FAULT_INJECTING_FILE_SYSTEM_H_
#define PDSM_CORE_UTIL_FAULT_INJECTING_FILE_SYSTEM_H_

#include <cerrno>
#include <cstdint>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <string>

#include "core/util/file_system.h"

namespace pdsm {

enum class FileOp {
  kCreate,   // FileSystem::NewTempFile, NewScratchFile, OpenFile
  kWrite,    // WritableFile::WriteAt, ScratchFile::WriteAt, RandomAccessFile::WriteAt, Truncate
  kFlush,    // WritableFile::Flush
  kSync,     // WritableFile::Sync, RandomAccessFile::Sync
  kClose,    // WritableFile::Close
  kRename,   // FileSystem::RenameFile
  kSyncDir,  // FileSystem::SyncDir
};

const char* FileOpName(FileOp op);

// Thread-safe. Removing files is never broken: that is how writers clean up.
class FaultInjectingFileSystem final : public FileSystemWrapper {
 public:
  // `target` must outlive this object and the files it creates.
  explicit FaultInjectingFileSystem(FileSystem* target = FileSystem::Default());

  // The `n`th call of `op` from now (1 = the next) fails with `error_number`, without
  // reaching the real file system; one failure per op is armed at a time.
  void FailNth(FileOp op, int n, int error_number = EIO);
  // Writes fail with ENOSPC once `bytes` more bytes have been written through this object;
  // the write that crosses the limit writes the part that fits first, as a full disk does.
  void SetDiskFullAfter(uint64_t bytes);
  // Disarms every failure and zeroes the counters.
  void Reset();

  // Calls of `op` made through this object since construction or Reset(), failed ones
  // included.
  int op_count(FileOp op) const;
  // Injected failures that fired since construction or Reset().
  int failures() const;
  // Bytes handed to the real file system by writes since construction or Reset().
  uint64_t bytes_written() const;

  absl::StatusOr<std::unique_ptr<WritableFile>> NewTempFile(const std::string& target) override;
  absl::StatusOr<std::unique_ptr<ScratchFile>> NewScratchFile(const std::string& dir) override;
  absl::StatusOr<std::unique_ptr<RandomAccessFile>> OpenFile(const std::string& path) override;
  absl::Status RenameFile(const std::string& from, const std::string& to) override;
  absl::Status SyncDir(const std::string& dir) override;

 private:
  class File;
  class Scratch;
  class InPlace;

  // A write of `data` through `file` (a WritableFile or a ScratchFile), failing as armed:
  // the injected error, or a full disk that takes what fits first.
  template <typename Target>
  absl::Status Write(Target& file, const std::string& name, uint64_t offset,
                     absl::string_view data);
  // Counts a call of `op`; the injected error if this is the armed one, else OK.
  absl::Status Check(FileOp op, const std::string& name);
  // How many of `size` bytes fit before the disk is full.
  uint64_t Reserve(uint64_t size);

  mutable std::mutex mu_;
  // All guarded by mu_.
  std::map<FileOp, int> counts_;
  std::map<FileOp, std::pair<int, int>> armed_;  // op -> (call number, errno)
  uint64_t bytes_left_ = std::numeric_limits<uint64_t>::max();
  int failures_ = 0;
  uint64_t bytes_written_ = 0;
};

}  // namespace pdsm

#endif  // PDSM_CORE_UTIL_FAULT_INJECTING_FILE_SYSTEM_H_
