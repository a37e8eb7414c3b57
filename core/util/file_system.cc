#include "core/util/file_system.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstddef>
#include <filesystem>
#include <random>

#include "absl/strings/str_cat.h"

namespace pdsm {
namespace {

// The status of the errno now, for "<action> <name>": errno is read before the message is built.
absl::Status LastErrnoStatus(absl::string_view action, const std::string& name) {
  const int error_number = errno;
  return ErrnoStatus(error_number, absl::StrCat(action, " ", name));
}

// Writes are gathered up to this size: OpenEXR writes a tile as several small pieces.
constexpr size_t kBufferBytes = 64 * 1024;

class PosixWritableFile final : public WritableFile {
 public:
  PosixWritableFile(int fd, std::string path) : fd_(fd), path_(std::move(path)) {}
  ~PosixWritableFile() override {
    if (fd_ >= 0) ::close(fd_);
  }

  absl::Status WriteAt(uint64_t offset, absl::string_view data) override {
    if (!buffer_.empty() && offset != buffer_offset_ + buffer_.size()) {
      if (absl::Status s = Flush(); !s.ok()) return s;
    }
    if (buffer_.empty()) buffer_offset_ = offset;
    if (buffer_.size() + data.size() <= kBufferBytes) {
      buffer_.append(data.data(), data.size());
      return absl::OkStatus();
    }
    if (absl::Status s = Flush(); !s.ok()) return s;
    return WriteFully(offset, data);
  }

  absl::Status Flush() override {
    if (buffer_.empty()) return absl::OkStatus();
    absl::Status status = WriteFully(buffer_offset_, buffer_);
    buffer_.clear();
    return status;
  }

  absl::Status Sync() override {
    if (absl::Status s = Flush(); !s.ok()) return s;
    if (::fsync(fd_) != 0) return LastErrnoStatus("cannot sync", path_);
    return absl::OkStatus();
  }

  absl::Status Close() override {
    absl::Status status = Flush();
    // close() is not retried on EINTR: on Linux the descriptor is gone either way.
    if (::close(fd_) != 0 && status.ok()) status = LastErrnoStatus("cannot close", path_);
    fd_ = -1;
    return status;
  }

  const std::string& path() const override { return path_; }

 private:
  absl::Status WriteFully(uint64_t offset, absl::string_view data) {
    while (!data.empty()) {
      const ssize_t n = ::pwrite(fd_, data.data(), data.size(), static_cast<off_t>(offset));
      if (n < 0) {
        if (errno == EINTR) continue;
        return LastErrnoStatus("cannot write", path_);
      }
      data.remove_prefix(static_cast<size_t>(n));
      offset += static_cast<uint64_t>(n);
    }
    return absl::OkStatus();
  }

  int fd_;
  const std::string path_;
  std::string buffer_;  // bytes for [buffer_offset_, buffer_offset_ + size)
  uint64_t buffer_offset_ = 0;
};

// Six letters and digits, as mkstemp's XXXXXX.
std::string RandomSuffix() {
  static constexpr char kChars[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789";
  thread_local std::mt19937_64 rng(std::random_device{}());
  std::string suffix(6, '\0');
  for (char& c : suffix) c = kChars[rng() % (sizeof(kChars) - 1)];
  return suffix;
}

class PosixFileSystem final : public FileSystem {
 public:
  absl::StatusOr<std::unique_ptr<WritableFile>> NewTempFile(const std::string& target) override {
    // Not mkstemp: it creates with mode 0600. open() with 0666 lets the umask decide, as for
    // any new file; O_EXCL keeps the name ours.
    for (int attempt = 0; attempt < 100; ++attempt) {
      std::string name = absl::StrCat(target, ".tmp-", RandomSuffix());
      const int fd = ::open(name.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
      if (fd >= 0) return std::make_unique<PosixWritableFile>(fd, std::move(name));
      if (errno == EEXIST) continue;
      const int error_number = errno;
      return ErrnoStatus(error_number, absl::StrCat("cannot create a temporary file for ", target,
                                                    " in ", ParentDir(target)));
    }
    return absl::AlreadyExistsError(absl::StrCat("no free temporary name for ", target));
  }

  absl::Status RenameFile(const std::string& from, const std::string& to) override {
    if (::rename(from.c_str(), to.c_str()) != 0) {
      const int error_number = errno;
      return ErrnoStatus(error_number, absl::StrCat("cannot rename ", from, " to ", to));
    }
    return absl::OkStatus();
  }

  absl::Status SyncDir(const std::string& dir) override {
    const std::string name = dir.empty() ? "." : dir;
    const int fd = ::open(name.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd < 0) return LastErrnoStatus("cannot open to sync the folder", name);
    absl::Status status;
    if (::fsync(fd) != 0) status = LastErrnoStatus("cannot sync the folder", name);
    ::close(fd);
    return status;
  }

  absl::Status RemoveFile(const std::string& path) override {
    if (::unlink(path.c_str()) != 0) return LastErrnoStatus("cannot remove", path);
    return absl::OkStatus();
  }
};

}  // namespace

absl::Status ErrnoStatus(int error_number, absl::string_view message) {
  return error_number != 0 ? absl::ErrnoToStatus(error_number, message)
                           : absl::UnknownError(message);
}

FileSystem* FileSystem::Default() {
  static FileSystem* const file_system = new PosixFileSystem;
  return file_system;
}

std::string ParentDir(const std::string& path) {
  const std::filesystem::path parent = std::filesystem::path(path).parent_path();
  return parent.empty() ? std::string(".") : parent.string();
}

}  // namespace pdsm
