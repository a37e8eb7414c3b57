#include "core/util/atomic_file.h"

#include <algorithm>
#include <utility>

#include "absl/strings/str_cat.h"

namespace pdsm {

absl::StatusOr<std::unique_ptr<AtomicFile>> AtomicFile::Create(const std::string& path,
                                                               FileSystem* fs) {
  if (fs == nullptr) fs = FileSystem::Default();
  absl::StatusOr<std::unique_ptr<WritableFile>> file = fs->NewTempFile(path);
  if (!file.ok()) return file.status();
  return std::unique_ptr<AtomicFile>(new AtomicFile(path, fs, *std::move(file)));
}

AtomicFile::AtomicFile(std::string path, FileSystem* fs, std::unique_ptr<WritableFile> file)
    : path_(std::move(path)), temp_path_(file->path()), fs_(fs), file_(std::move(file)) {}

AtomicFile::~AtomicFile() {
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
  absl::Status closed = file_->Close();
  file_.reset();
  if (!closed.ok()) return Fail(closed);
  if (absl::Status s = fs_->RenameFile(temp_path_, path_); !s.ok()) return Fail(s);
  committed_ = true;
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
  file_.reset();  // closes; errors do not matter, the file goes
  fs_->RemoveFile(temp_path_).IgnoreError();
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
