// The one way the project writes a file, so that readers see the old file or the new one and
// never part of one, even across a crash: the bytes go to a fresh temporary file beside the
// target ("<target>.tmp-XXXXXX", file_system.h), are synced, the temporary file is renamed
// onto the target, and the target's folder is synced so that the rename is durable too.
// AtomicFile streams (the PDSM is written tile by tile, never held whole in memory);
// WriteFileAtomically writes bytes already in memory.
//
// What an interrupted writer leaves: nothing once it unwinds (failure, destruction); nothing
// after SIGINT, SIGTERM or SIGHUP in a binary that called RemoveTempFilesOnTerminationSignals
// (termination_cleanup.h), where every temporary file in flight is registered; after a
// SIGKILL or a crash, a "<target>.tmp-XXXXXX" that the first AtomicFile::Create in the same
// folder by any later process removes (FileSystem::RemoveStaleTempFiles: only files whose
// writer is gone, known by the lock every live writer holds on its file).
#ifndef PDSM_CORE_UTIL_ATOMIC_FILE_H_
#define PDSM_CORE_UTIL_ATOMIC_FILE_H_

#include <cstdint>
#include <memory>
#include <string>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "core/util/file_system.h"

namespace pdsm {

// A file being written to replace `path` at Commit(). Not thread-safe.
//
// State on failure: the first error of any call removes the temporary file at once and is
// returned again by every later call; `path` is left as it was. Destroying an AtomicFile that
// was not committed removes the temporary file too (an abandoned write leaves nothing).
// Errors are those of the FileSystem (ErrnoStatus codes: RESOURCE_EXHAUSTED for a full disk,
// NOT_FOUND for a missing folder, …); each message names the target or its temporary file,
// whose name begins with the target's.
class AtomicFile {
 public:
  // Creates the temporary file. `fs` null means FileSystem::Default(); it must outlive the
  // AtomicFile. The first call of a process for a folder first removes the stale temporary
  // files there (FileSystem::RemoveStaleTempFiles). FAILED_PRECONDITION when `path` exists
  // and is not a regular file (CheckReplaceable: a device, a folder, a FIFO, a link): the
  // rename would replace that node.
  static absl::StatusOr<std::unique_ptr<AtomicFile>> Create(const std::string& path,
                                                            FileSystem* fs = nullptr);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  // Writes `data` at the end of what was written so far.
  absl::Status Append(absl::string_view data);
  // Writes `data` at byte `offset`, possibly over bytes written before (a format's table of
  // contents, patched at the end). The size becomes max(size(), offset + data.size()).
  absl::Status WriteAt(uint64_t offset, absl::string_view data);
  // Makes the bytes written so far readable through temp_path() (not durable): for a writer
  // that reads back its own temporary file.
  absl::Status Flush();

  // Gives the write up now, as destruction would: the temporary file goes, and every later
  // call returns CANCELLED without touching the file system (a format library that writes its
  // trailer from its destructor then writes nothing). No-op once committed or failed.
  void Abandon();
  // Syncs and closes the temporary file, renames it onto `path`, syncs the folder.
  // REQUIRES: not committed yet. A failure before the rename leaves `path` as it was; a
  // failure of the folder sync comes after it, so `path` then holds the whole new file but
  // the rename may not survive a crash. No temporary file is left either way.
  absl::Status Commit();

  const std::string& path() const { return path_; }
  // The temporary file's name; nothing is there after Commit() or a failure.
  const std::string& temp_path() const { return temp_path_; }
  // Bytes written: the highest offset reached.
  uint64_t size() const { return size_; }
  // OK, or the first error.
  const absl::Status& status() const { return status_; }

 private:
  AtomicFile(std::string path, FileSystem* fs, std::unique_ptr<WritableFile> file);

  // Records the first error and removes the temporary file.
  absl::Status Fail(absl::Status status);

  const std::string path_;
  const std::string temp_path_;
  FileSystem* const fs_;
  std::unique_ptr<WritableFile> file_;  // null once renamed or removed (holds the lock until)
  int cleanup_handle_ = -1;             // RegisterTempFile's, while the temporary file exists
  uint64_t size_ = 0;
  absl::Status status_;
  bool committed_ = false;
};

// Writes `contents` to `path` through an AtomicFile. `fs` null means FileSystem::Default().
// Errors and state on failure: those of AtomicFile (`path` unchanged, no temporary file).
absl::Status WriteFileAtomically(const std::string& path, absl::string_view contents,
                                 FileSystem* fs = nullptr);

}  // namespace pdsm

#endif  // PDSM_CORE_UTIL_ATOMIC_FILE_H_
