// The one seam between the project and the file system for every file it writes (leveldb's
// Env is the model): a FileSystem creates temporary files, renames them, syncs folders and
// removes files; FileSystem::Default() does it with POSIX calls, and a FileSystemWrapper
// forwards to another one so that a test double (fault_injecting_file_system.h) overrides
// only what it breaks. Writers never call these directly: they go through AtomicFile
// (atomic_file.h), which orders the steps so that a target is always whole.
#ifndef PDSM_CORE_UTIL_FILE_SYSTEM_H_
#define PDSM_CORE_UTIL_FILE_SYSTEM_H_

#include <cstdint>
#include <memory>
#include <string>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"

namespace pdsm {

// The status of a failed system call: its code from the errno (ENOSPC → RESOURCE_EXHAUSTED,
// ENOENT → NOT_FOUND, EACCES → PERMISSION_DENIED, …, as absl::ErrnoToStatus maps them), its
// message "<message>: <strerror>". UNKNOWN for an errno of 0. Read errno before building
// `message`: formatting can change it.
absl::Status ErrnoStatus(int error_number, absl::string_view message);

// A file open for writing. Not thread-safe; one owner writes it. Every error names the file.
// After an error the file's content is unspecified.
class WritableFile {
 public:
  WritableFile() = default;
  WritableFile(const WritableFile&) = delete;
  WritableFile& operator=(const WritableFile&) = delete;
  // Closes the file if Close() was not called, ignoring errors.
  virtual ~WritableFile() = default;

  // Writes `data` at byte `offset` (pwrite): formats that patch bytes written earlier
  // (OpenEXR's tile offset table) seek back. Writes may be buffered until Flush/Sync/Close.
  virtual absl::Status WriteAt(uint64_t offset, absl::string_view data) = 0;
  // Hands buffered bytes to the operating system: readable by name, not yet durable.
  virtual absl::Status Flush() = 0;
  // Flushes, then fsync: the bytes are on the disk.
  virtual absl::Status Sync() = 0;
  // Flushes and closes. REQUIRES: called at most once; no call but the destructor after it.
  virtual absl::Status Close() = 0;

  // The file's name as created.
  virtual const std::string& path() const = 0;
};

// A file for the process's own scratch data (a bake's event runs that do not fit in memory):
// it has no name, so nothing is left to remove however the process ends (SIGKILL included),
// and its blocks go back to the file system when it is destroyed. Thread-safe: reads and
// writes at offsets (pread, pwrite) need no lock. Every error names the file's folder.
class ScratchFile {
 public:
  ScratchFile() = default;
  ScratchFile(const ScratchFile&) = delete;
  ScratchFile& operator=(const ScratchFile&) = delete;
  virtual ~ScratchFile() = default;

  // Writes `data` at byte `offset`, unbuffered.
  virtual absl::Status WriteAt(uint64_t offset, absl::string_view data) = 0;
  // Reads `size` bytes at `offset` into `out`. DATA_LOSS when the file ends first.
  virtual absl::Status ReadAt(uint64_t offset, size_t size, char* out) = 0;
  // Bytes [offset, offset + size) are not needed again: their blocks may go back to the file
  // system (a hole is punched where it can be; otherwise nothing happens).
  virtual void Release(uint64_t offset, uint64_t size) = 0;

  // "<folder> (scratch file)", for messages.
  virtual const std::string& label() const = 0;
};

// A named file kept open to be written in place and read back (the coordinator's tile log,
// server/tile_log.h, which appends records and cuts off a torn one). Writes are unbuffered;
// Sync makes them durable. Thread-safe: reads and writes at offsets (pread, pwrite) need no
// lock; the owner orders its writes. Every error names the file.
class RandomAccessFile {
 public:
  RandomAccessFile() = default;
  RandomAccessFile(const RandomAccessFile&) = delete;
  RandomAccessFile& operator=(const RandomAccessFile&) = delete;
  virtual ~RandomAccessFile() = default;

  // The file's length in bytes now.
  virtual absl::StatusOr<uint64_t> Size() = 0;
  // Writes `data` at byte `offset`.
  virtual absl::Status WriteAt(uint64_t offset, absl::string_view data) = 0;
  // Reads `size` bytes at `offset` into `out`. DATA_LOSS when the file ends first.
  virtual absl::Status ReadAt(uint64_t offset, size_t size, char* out) = 0;
  // Cuts the file to `size` bytes (ftruncate).
  virtual absl::Status Truncate(uint64_t size) = 0;
  // fdatasync: every byte written, and the length, are on the disk.
  virtual absl::Status Sync() = 0;

  virtual const std::string& path() const = 0;
};

// Thread-safe: every method may be called from any thread (the implementations hold no
// mutable state, or lock it).
class FileSystem {
 public:
  FileSystem() = default;
  FileSystem(const FileSystem&) = delete;
  FileSystem& operator=(const FileSystem&) = delete;
  virtual ~FileSystem() = default;

  // The real file system (POSIX). Never null, never destroyed.
  static FileSystem* Default();

  // Creates a new, empty file named "<target>.tmp-XXXXXX" (six random letters and digits,
  // created exclusively: concurrent writers of one target never share a name) in the folder
  // of `target`, with the mode a new file gets (0666 less the umask; not mkstemp's 0600).
  // The file is locked (flock, exclusive) from its creation until the WritableFile is
  // destroyed — Close() ends the writing, not the lock — so RemoveStaleTempFiles never takes
  // the file of a live writer, whichever process it is in; the kernel drops the lock when the
  // process dies, even by SIGKILL.
  // Errors: the errno's status (NOT_FOUND when the folder does not exist, PERMISSION_DENIED
  // when it cannot be written), naming `target`.
  virtual absl::StatusOr<std::unique_ptr<WritableFile>> NewTempFile(const std::string& target) = 0;

  // Removes what writers that died left behind: every entry of `dir` ("" is ".") whose name
  // is a temporary name of NewTempFile (IsTempFileName), that is a regular file of this user
  // (not followed if a link) and whose lock no process holds. Best effort: an entry that
  // cannot be checked or removed is left. Returns how many files were removed.
  virtual int RemoveStaleTempFiles(const std::string& dir) = 0;

  // A new, empty scratch file in the folder `dir` ("" is "."), readable and writable by this
  // user only. Errors: the errno's status (NOT_FOUND when the folder does not exist,
  // PERMISSION_DENIED when it cannot be written), naming `dir`.
  virtual absl::StatusOr<std::unique_ptr<ScratchFile>> NewScratchFile(const std::string& dir) = 0;

  // Opens `path` to read and write it in place, creating it empty (with the mode a new file
  // gets) when there is none; a new file's folder is synced, so that its name is durable.
  // Errors: the errno's status (NOT_FOUND when the folder does not exist), naming `path`.
  virtual absl::StatusOr<std::unique_ptr<RandomAccessFile>> OpenFile(const std::string& path) = 0;

  // rename(2): replaces `to` atomically; a reader sees the old file or the new one.
  virtual absl::Status RenameFile(const std::string& from, const std::string& to) = 0;
  // fsync of the folder `dir` ("" is "."): makes the entries renamed or created in it durable.
  virtual absl::Status SyncDir(const std::string& dir) = 0;
  // unlink(2). NOT_FOUND when there is no such file.
  virtual absl::Status RemoveFile(const std::string& path) = 0;
};

// Forwards every call to `target` (leveldb's EnvWrapper): a subclass overrides only what it
// changes. Does not own `target`, which must outlive it.
class FileSystemWrapper : public FileSystem {
 public:
  explicit FileSystemWrapper(FileSystem* target) : target_(target) {}

  FileSystem* target() const { return target_; }

  absl::StatusOr<std::unique_ptr<WritableFile>> NewTempFile(const std::string& target) override {
    return target_->NewTempFile(target);
  }
  absl::StatusOr<std::unique_ptr<ScratchFile>> NewScratchFile(const std::string& dir) override {
    return target_->NewScratchFile(dir);
  }
  absl::StatusOr<std::unique_ptr<RandomAccessFile>> OpenFile(const std::string& path) override {
    return target_->OpenFile(path);
  }
  absl::Status RenameFile(const std::string& from, const std::string& to) override {
    return target_->RenameFile(from, to);
  }
  absl::Status SyncDir(const std::string& dir) override { return target_->SyncDir(dir); }
  absl::Status RemoveFile(const std::string& path) override { return target_->RemoveFile(path); }
  int RemoveStaleTempFiles(const std::string& dir) override {
    return target_->RemoveStaleTempFiles(dir);
  }

 private:
  FileSystem* const target_;
};

// The folder holding `path`, "." for a bare name: what SyncDir must sync after a rename.
std::string ParentDir(const std::string& path);

// True for a file name (no folder) that NewTempFile makes: at least one character, then
// ".tmp-" and exactly six ASCII letters or digits at the end.
bool IsTempFileName(absl::string_view file_name);

// Whether a writer may replace `path` by renaming a new file onto it: OK when nothing is
// there or it is a regular file. FAILED_PRECONDITION naming `path` and what it is otherwise
// (a folder, a device such as /dev/full, a FIFO, a socket, a symbolic link — a rename would
// replace the node itself, not write through it). Not followed: a link is refused whatever
// it points to.
absl::Status CheckReplaceable(const std::string& path);

}  // namespace pdsm

#endif  // PDSM_CORE_UTIL_FILE_SYSTEM_H_
