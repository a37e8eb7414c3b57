#include "core/util/fault_injecting_file_system.h"

#include <algorithm>
#include <utility>

#include "absl/strings/str_cat.h"

namespace pdsm {

const char* FileOpName(FileOp op) {
  switch (op) {
    case FileOp::kCreate:
      return "create";
    case FileOp::kWrite:
      return "write";
    case FileOp::kFlush:
      return "flush";
    case FileOp::kSync:
      return "sync";
    case FileOp::kClose:
      return "close";
    case FileOp::kRename:
      return "rename";
    case FileOp::kSyncDir:
      return "sync folder";
  }
  return "?";
}

// A real file whose calls go through the owner's checks first.
class FaultInjectingFileSystem::File final : public WritableFile {
 public:
  File(FaultInjectingFileSystem* owner, std::unique_ptr<WritableFile> file)
      : owner_(owner), file_(std::move(file)) {}

  absl::Status WriteAt(uint64_t offset, absl::string_view data) override {
    return owner_->Write(*file_, path(), offset, data);
  }
  absl::Status Flush() override {
    if (absl::Status s = owner_->Check(FileOp::kFlush, path()); !s.ok()) return s;
    return file_->Flush();
  }
  absl::Status Sync() override {
    if (absl::Status s = owner_->Check(FileOp::kSync, path()); !s.ok()) return s;
    return file_->Sync();
  }
  absl::Status Close() override {
    // The descriptor is released even when the close "fails", as close(2) does.
    absl::Status injected = owner_->Check(FileOp::kClose, path());
    absl::Status closed = file_->Close();
    return injected.ok() ? closed : injected;
  }
  const std::string& path() const override { return file_->path(); }

 private:
  FaultInjectingFileSystem* const owner_;
  std::unique_ptr<WritableFile> file_;
};

// A real scratch file whose writes go through the owner's checks first (reads are never
// broken: the data was written).
class FaultInjectingFileSystem::Scratch final : public ScratchFile {
 public:
  Scratch(FaultInjectingFileSystem* owner, std::unique_ptr<ScratchFile> file)
      : owner_(owner), file_(std::move(file)) {}

  absl::Status WriteAt(uint64_t offset, absl::string_view data) override {
    return owner_->Write(*file_, label(), offset, data);
  }
  absl::Status ReadAt(uint64_t offset, size_t size, char* out) override {
    return file_->ReadAt(offset, size, out);
  }
  void Release(uint64_t offset, uint64_t size) override { file_->Release(offset, size); }
  const std::string& label() const override { return file_->label(); }

 private:
  FaultInjectingFileSystem* const owner_;
  std::unique_ptr<ScratchFile> file_;
};

// A real file written in place whose writes and syncs go through the owner's checks first
// (reads are never broken).
class FaultInjectingFileSystem::InPlace final : public RandomAccessFile {
 public:
  InPlace(FaultInjectingFileSystem* owner, std::unique_ptr<RandomAccessFile> file)
      : owner_(owner), file_(std::move(file)) {}

  absl::StatusOr<uint64_t> Size() override { return file_->Size(); }
  absl::Status WriteAt(uint64_t offset, absl::string_view data) override {
    return owner_->Write(*file_, path(), offset, data);
  }
  absl::Status ReadAt(uint64_t offset, size_t size, char* out) override {
    return file_->ReadAt(offset, size, out);
  }
  absl::Status Truncate(uint64_t size) override {
    if (absl::Status s = owner_->Check(FileOp::kWrite, path()); !s.ok()) return s;
    return file_->Truncate(size);
  }
  absl::Status Sync() override {
    if (absl::Status s = owner_->Check(FileOp::kSync, path()); !s.ok()) return s;
    return file_->Sync();
  }
  const std::string& path() const override { return file_->path(); }

 private:
  FaultInjectingFileSystem* const owner_;
  std::unique_ptr<RandomAccessFile> file_;
};

FaultInjectingFileSystem::FaultInjectingFileSystem(FileSystem* target)
    : FileSystemWrapper(target) {}

void FaultInjectingFileSystem::FailNth(FileOp op, int n, int error_number) {
  std::lock_guard<std::mutex> lock(mu_);
  armed_[op] = {counts_[op] + n, error_number};
}

void FaultInjectingFileSystem::SetDiskFullAfter(uint64_t bytes) {
  std::lock_guard<std::mutex> lock(mu_);
  bytes_left_ = bytes;
}

void FaultInjectingFileSystem::Reset() {
  std::lock_guard<std::mutex> lock(mu_);
  counts_.clear();
  armed_.clear();
  bytes_left_ = std::numeric_limits<uint64_t>::max();
  failures_ = 0;
  bytes_written_ = 0;
}

int FaultInjectingFileSystem::op_count(FileOp op) const {
  std::lock_guard<std::mutex> lock(mu_);
  const auto it = counts_.find(op);
  return it == counts_.end() ? 0 : it->second;
}

int FaultInjectingFileSystem::failures() const {
  std::lock_guard<std::mutex> lock(mu_);
  return failures_;
}

uint64_t FaultInjectingFileSystem::bytes_written() const {
  std::lock_guard<std::mutex> lock(mu_);
  return bytes_written_;
}

template <typename Target>
absl::Status FaultInjectingFileSystem::Write(Target& file, const std::string& name, uint64_t offset,
                                             absl::string_view data) {
  if (absl::Status s = Check(FileOp::kWrite, name); !s.ok()) return s;
  const uint64_t fits = Reserve(data.size());
  if (fits < data.size()) {
    // A full disk takes what fits, then refuses the rest.
    file.WriteAt(offset, data.substr(0, fits)).IgnoreError();
    return ErrnoStatus(ENOSPC, absl::StrCat("cannot write ", name, " (injected)"));
  }
  return file.WriteAt(offset, data);
}

absl::Status FaultInjectingFileSystem::Check(FileOp op, const std::string& name) {
  std::lock_guard<std::mutex> lock(mu_);
  const int call = ++counts_[op];
  const auto it = armed_.find(op);
  if (it == armed_.end() || it->second.first != call) return absl::OkStatus();
  const int error_number = it->second.second;
  armed_.erase(it);
  ++failures_;
  return ErrnoStatus(error_number,
                     absl::StrCat("cannot ", FileOpName(op), " ", name, " (injected)"));
}

uint64_t FaultInjectingFileSystem::Reserve(uint64_t size) {
  std::lock_guard<std::mutex> lock(mu_);
  const uint64_t fits = std::min(size, bytes_left_);
  bytes_left_ -= fits;
  bytes_written_ += fits;
  if (fits < size) ++failures_;
  return fits;
}

absl::StatusOr<std::unique_ptr<WritableFile>> FaultInjectingFileSystem::NewTempFile(
    const std::string& target) {
  if (absl::Status s = Check(FileOp::kCreate, target); !s.ok()) return s;
  absl::StatusOr<std::unique_ptr<WritableFile>> file = FileSystemWrapper::NewTempFile(target);
  if (!file.ok()) return file.status();
  return std::make_unique<File>(this, *std::move(file));
}

absl::StatusOr<std::unique_ptr<ScratchFile>> FaultInjectingFileSystem::NewScratchFile(
    const std::string& dir) {
  if (absl::Status s = Check(FileOp::kCreate, dir); !s.ok()) return s;
  absl::StatusOr<std::unique_ptr<ScratchFile>> file = FileSystemWrapper::NewScratchFile(dir);
  if (!file.ok()) return file.status();
  return std::make_unique<Scratch>(this, *std::move(file));
}

absl::StatusOr<std::unique_ptr<RandomAccessFile>> FaultInjectingFileSystem::OpenFile(
    const std::string& path) {
  if (absl::Status s = Check(FileOp::kCreate, path); !s.ok()) return s;
  absl::StatusOr<std::unique_ptr<RandomAccessFile>> file = FileSystemWrapper::OpenFile(path);
  if (!file.ok()) return file.status();
  return std::make_unique<InPlace>(this, *std::move(file));
}

absl::Status FaultInjectingFileSystem::RenameFile(const std::string& from, const std::string& to) {
  if (absl::Status s = Check(FileOp::kRename, absl::StrCat(from, " to ", to)); !s.ok()) return s;
  return FileSystemWrapper::RenameFile(from, to);
}

absl::Status FaultInjectingFileSystem::SyncDir(const std::string& dir) {
  if (absl::Status s = Check(FileOp::kSyncDir, dir); !s.ok()) return s;
  return FileSystemWrapper::SyncDir(dir);
}

}  // namespace pdsm
