#include "core/util/atomic_file.h"

#include <algorithm>
#include <set>
#include <utility>

#include "absl/base/thread_annotations.h"
#include "absl/strings/str_cat.h"
#include "absl/synchronization/mutex.h"
#include "core/util/termination_cleanup.h"

namespace pdsm {

namespace {

// Runs fs->RemoveStaleTempFiles(dir) the first time this process writes into `dir` (as
// spelled: another spelling of the same folder only sweeps it twice).
void SweepFolderOnce(FileSystem* fs, const std::string& dir) {
  static absl::Mutex mu(absl::kConstInit);
  static std::set<std::string>* swept ABSL_GUARDED_BY(mu) = new std::set<std::string>;
  {
    absl::MutexLock lock(&mu);
    if (!swept->insert(dir).second) return;
  }
  fs->RemoveStaleTempFiles(dir);
}

}  // namespace

absl::StatusOr<std::unique_ptr<AtomicFile>> AtomicFile::Create(const std::string& path,
                                                               FileSystem* fs) {
  if (fs == nullptr) fs = FileSystem::Default();
  if (absl::Status s = CheckReplaceable(path); !s.ok()) return s;
  SweepFolderOnce(fs, ParentDir(path));
  absl::StatusOr<std::unique_ptr<WritableFile>> file = fs->NewTempFile(path);
  if (!file.ok()) return file.status();
  return std::unique_ptr<AtomicFile>(new AtomicFile(path, fs, *std::move(file)));
}

AtomicFile::AtomicFile(std::string path, FileSystem* fs, std::unique_ptr<WritableFile> file)
    : path_(std::move(path)),
      temp_path_(file->path()),
      fs_(fs),
      file_(std::move(file)),
      cleanup_handle_(RegisterTempFile(temp_path_)) {}

AtomicFile::~AtomicFile() { Abandon(); }

void AtomicFile::Abandon() {
  if (!committed_ && status_.ok()) Fail(absl::CancelledError("abandoned")).IgnoreError();
}

absl::Status AtomicFile::Append(absl::string_view data) { return WriteAt(size_, data); }

absl::Status AtomicFile::WriteAt(uint64_t offset, absl::string_view data) {
  if (!status_.ok()) return status_;
  if (committed_) return absl::FailedPreconditionError(path_ + ": already committed");
  if (absl::Status s = file_->WriteAt(offset, data); !s.ok()) return Fail(s);
  size_ = std::max(size_, offset + data.size());
  return absl::OkStatus();
}

absl::Status AtomicFile::Flush() {
  if (!status_.ok()) return status_;
  if (committed_) return absl::FailedPreconditionError(path_ + ": already committed");
  if (absl::Status s = file_->Flush(); !s.ok()) return Fail(s);
  return absl::OkStatus();
}

absl::Status AtomicFile::Commit() {
  if (!status_.ok()) return status_;
  if (committed_) return absl::FailedPreconditionError(path_ + ": already committed");
  // fsync before the rename: a crash must not leave a renamed file with missing bytes.
  if (absl::Status s = file_->Sync(); !s.ok()) return Fail(s);
  if (absl::Status s = file_->Close(); !s.ok()) return Fail(s);
  // Checked again just before the rename: the target may have changed since Create().
  if (absl::Status s = CheckReplaceable(path_); !s.ok()) return Fail(s);
  if (absl::Status s = fs_->RenameFile(temp_path_, path_); !s.ok()) return Fail(s);
  committed_ = true;
  UnregisterTempFile(cleanup_handle_);
  cleanup_handle_ = -1;
  file_.reset();  // drops the lock: the temporary name is gone
  // The rename is in the folder's entries: durable only once the folder is synced.
  if (absl::Status s = fs_->SyncDir(ParentDir(path_)); !s.ok()) {
    status_ = absl::Status(
        s.code(), absl::StrCat(s.message(), " (after renaming ", temp_path_, " to ", path_, ")"));
    return status_;
  }
  return absl::OkStatus();
}

absl::Status AtomicFile::Fail(absl::Status status) {
  status_ = std::move(status);
  // Removed while still locked, then closed (errors do not matter, the file goes).
  fs_->RemoveFile(temp_path_).IgnoreError();
  UnregisterTempFile(cleanup_handle_);
  cleanup_handle_ = -1;
  file_.reset();
  return status_;
}

absl::Status WriteFileAtomically(const std::string& path, absl::string_view contents,
                                 FileSystem* fs) {
  absl::StatusOr<std::unique_ptr<AtomicFile>> file = AtomicFile::Create(path, fs);
  if (!file.ok()) return file.status();
  if (absl::Status s = (*file)->Append(contents); !s.ok()) return s;
  return (*file)->Commit();
}

}  // namespace pdsm
