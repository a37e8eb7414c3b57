#include "core/util/file_system.h"

#include <dirent.h>
#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstddef>
#include <filesystem>
#include <random>

#include "absl/strings/ascii.h"
#include "absl/strings/str_cat.h"

namespace pdsm {
namespace {

// The status of the errno now, for "<action> <name>": errno is read before the message is built.
absl::Status LastErrnoStatus(absl::string_view action, const std::string& name) {
  const int error_number = errno;
  return ErrnoStatus(error_number, absl::StrCat(action, " ", name));
}

// pwrite(2) until every byte is written (it may write less), retrying on EINTR; errors name
// `name`.
absl::Status PwriteFully(int fd, uint64_t offset, absl::string_view data, const std::string& name) {
  while (!data.empty()) {
    const ssize_t n = ::pwrite(fd, data.data(), data.size(), static_cast<off_t>(offset));
    if (n < 0) {
      if (errno == EINTR) continue;
      return LastErrnoStatus("cannot write", name);
    }
    data.remove_prefix(static_cast<size_t>(n));
    offset += static_cast<uint64_t>(n);
  }
  return absl::OkStatus();
}

// pread(2) until `size` bytes are read, retrying on EINTR. DATA_LOSS when the file ends first;
// errors name `name`.
absl::Status PreadFully(int fd, uint64_t offset, size_t size, char* out, const std::string& name) {
  while (size > 0) {
    const ssize_t n = ::pread(fd, out, size, static_cast<off_t>(offset));
    if (n < 0) {
      if (errno == EINTR) continue;
      return LastErrnoStatus("cannot read", name);
    }
    if (n == 0) {
      return absl::DataLossError(absl::StrCat(name, ": ends at byte ", offset, ", ", size,
                                              " bytes before the read's end"));
    }
    out += n;
    size -= static_cast<size_t>(n);
    offset += static_cast<uint64_t>(n);
  }
  return absl::OkStatus();
}

// Writes are gathered up to this size: OpenEXR writes a tile as several small pieces.
constexpr size_t kBufferBytes = 64 * 1024;

class PosixWritableFile final : public WritableFile {
 public:
  // `lock_fd`: a duplicate of `fd` (same open file, so the same flock), kept open after
  // Close() so that the file stays locked until this object goes.
  PosixWritableFile(int fd, int lock_fd, std::string path)
      : fd_(fd), lock_fd_(lock_fd), path_(std::move(path)) {}
  ~PosixWritableFile() override {
    if (fd_ >= 0) ::close(fd_);
    if (lock_fd_ >= 0) ::close(lock_fd_);
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
    return PwriteFully(fd_, offset, data, path_);
  }

  int fd_;
  const int lock_fd_;
  const std::string path_;
  std::string buffer_;  // bytes for [buffer_offset_, buffer_offset_ + size)
  uint64_t buffer_offset_ = 0;
};

class PosixScratchFile final : public ScratchFile {
 public:
  PosixScratchFile(int fd, std::string label) : fd_(fd), label_(std::move(label)) {}
  ~PosixScratchFile() override { ::close(fd_); }

  absl::Status WriteAt(uint64_t offset, absl::string_view data) override {
    return PwriteFully(fd_, offset, data, label_);
  }

  absl::Status ReadAt(uint64_t offset, size_t size, char* out) override {
    return PreadFully(fd_, offset, size, out, label_);
  }

  void Release(uint64_t offset, uint64_t size) override {
    // Best effort: a file system without holes keeps the blocks until the file is closed.
    ::fallocate(fd_, FALLOC_FL_PUNCH_HOLE | FALLOC_FL_KEEP_SIZE, static_cast<off_t>(offset),
                static_cast<off_t>(size));
  }

  const std::string& label() const override { return label_; }

 private:
  const int fd_;
  const std::string label_;
};

class PosixRandomAccessFile final : public RandomAccessFile {
 public:
  PosixRandomAccessFile(int fd, std::string path) : fd_(fd), path_(std::move(path)) {}
  ~PosixRandomAccessFile() override { ::close(fd_); }

  absl::StatusOr<uint64_t> Size() override {
    struct stat info;
    if (::fstat(fd_, &info) != 0) return LastErrnoStatus("cannot inspect", path_);
    return static_cast<uint64_t>(info.st_size);
  }
  absl::Status WriteAt(uint64_t offset, absl::string_view data) override {
    return PwriteFully(fd_, offset, data, path_);
  }
  absl::Status ReadAt(uint64_t offset, size_t size, char* out) override {
    return PreadFully(fd_, offset, size, out, path_);
  }
  absl::Status Truncate(uint64_t size) override {
    while (::ftruncate(fd_, static_cast<off_t>(size)) != 0) {
      if (errno != EINTR) return LastErrnoStatus("cannot truncate", path_);
    }
    return absl::OkStatus();
  }
  absl::Status Sync() override {
    if (::fdatasync(fd_) != 0) return LastErrnoStatus("cannot sync", path_);
    return absl::OkStatus();
  }
  const std::string& path() const override { return path_; }

 private:
  const int fd_;
  const std::string path_;
};

// Six letters and digits, as mkstemp's XXXXXX.
std::string RandomSuffix() {
  static constexpr char kChars[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789";
  thread_local std::mt19937_64 rng(std::random_device{}());
  std::string suffix(6, '\0');
  for (char& c : suffix) c = kChars[rng() % (sizeof(kChars) - 1)];
  return suffix;
}

// Whether `name` still names the file open as `fd` (a sweeper may have removed it between
// our open() and our lock).
bool StillNamed(int fd, const std::string& name) {
  struct stat open_file, named;
  return ::fstat(fd, &open_file) == 0 && ::lstat(name.c_str(), &named) == 0 &&
         open_file.st_dev == named.st_dev && open_file.st_ino == named.st_ino;
}

// Removes `path` if it is a stale temporary file: a regular file of ours whose lock we get.
// The lock is held across the unlink, so a writer that created the file a moment ago and is
// waiting for its lock sees the name gone (StillNamed) and picks another.
bool RemoveIfStale(const std::string& path) {
  struct stat entry;
  if (::lstat(path.c_str(), &entry) != 0 || !S_ISREG(entry.st_mode) ||
      entry.st_uid != ::geteuid()) {
    return false;
  }
  const int fd = ::open(path.c_str(), O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) return false;
  bool removed = false;
  if (::flock(fd, LOCK_EX | LOCK_NB) == 0 && StillNamed(fd, path)) {
    removed = ::unlink(path.c_str()) == 0;
  }
  ::close(fd);  // drops the lock
  return removed;
}

class PosixFileSystem final : public FileSystem {
 public:
  absl::StatusOr<std::unique_ptr<WritableFile>> NewTempFile(const std::string& target) override {
    // Not mkstemp: it creates with mode 0600. open() with 0666 lets the umask decide, as for
    // any new file; O_EXCL keeps the name ours.
    for (int attempt = 0; attempt < 100; ++attempt) {
      std::string name = absl::StrCat(target, ".tmp-", RandomSuffix());
      const int fd = ::open(name.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
      if (fd < 0) {
        if (errno == EEXIST) continue;
        const int error_number = errno;
        if (error_number == ENOENT) {  // the usual slip: an output folder not made yet
          return ErrnoStatus(error_number,
                             absl::StrCat("cannot write ", target, ": the folder ",
                                          ParentDir(target), " does not exist (create it first)"));
        }
        return ErrnoStatus(error_number, absl::StrCat("cannot create a temporary file for ", target,
                                                      " in ", ParentDir(target)));
      }
      // Blocking: only a sweeper that found the file before we locked it holds the lock, for
      // as long as it takes to remove it. Where the file system has no flock, the sweeper
      // cannot lock either and removes nothing, so the file is simply not locked.
      while (::flock(fd, LOCK_EX) != 0 && errno == EINTR) {
      }
      if (!StillNamed(fd, name)) {  // a sweeper took it before we locked it
        ::close(fd);
        continue;
      }
      const int lock_fd = ::fcntl(fd, F_DUPFD_CLOEXEC, 0);
      if (lock_fd < 0) {
        const int error_number = errno;
        ::unlink(name.c_str());
        ::close(fd);
        return ErrnoStatus(error_number, absl::StrCat("cannot lock ", name));
      }
      return std::make_unique<PosixWritableFile>(fd, lock_fd, std::move(name));
    }
    return absl::AlreadyExistsError(absl::StrCat("no free temporary name for ", target));
  }

  absl::StatusOr<std::unique_ptr<ScratchFile>> NewScratchFile(const std::string& dir) override {
    const std::string folder = dir.empty() ? "." : dir;
    std::string label = absl::StrCat(folder, " (scratch file)");
    // O_TMPFILE: a file that never had a name. Where the file system lacks it, a named one
    // is unlinked at once (only a crash in between can leave it, under a temporary name that
    // RemoveStaleTempFiles sweeps).
    int fd = ::open(folder.c_str(), O_TMPFILE | O_RDWR | O_CLOEXEC, 0600);
    if (fd < 0 && (errno == EOPNOTSUPP || errno == EISDIR || errno == EINVAL)) {
      for (int attempt = 0; attempt < 100 && fd < 0; ++attempt) {
        const std::string name = absl::StrCat(folder, "/pdsm-scratch.tmp-", RandomSuffix());
        fd = ::open(name.c_str(), O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
        if (fd >= 0) {
          ::unlink(name.c_str());
        } else if (errno != EEXIST) {
          break;
        }
      }
    }
    if (fd < 0) {
      const int error_number = errno;
      return ErrnoStatus(error_number, absl::StrCat("cannot create a scratch file in ", folder));
    }
    return std::make_unique<PosixScratchFile>(fd, std::move(label));
  }

  int RemoveStaleTempFiles(const std::string& dir) override {
    const std::string folder = dir.empty() ? "." : dir;
    DIR* listing = ::opendir(folder.c_str());
    if (listing == nullptr) return 0;
    int removed = 0;
    while (const dirent* entry = ::readdir(listing)) {
      if (!IsTempFileName(entry->d_name)) continue;
      if (RemoveIfStale(absl::StrCat(folder, "/", entry->d_name))) ++removed;
    }
    ::closedir(listing);
    return removed;
  }

  absl::StatusOr<std::unique_ptr<RandomAccessFile>> OpenFile(const std::string& path) override {
    int fd = ::open(path.c_str(), O_RDWR | O_CLOEXEC);
    if (fd < 0 && errno == ENOENT) {
      fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
      if (fd >= 0) {
        if (absl::Status s = SyncDir(ParentDir(path)); !s.ok()) {
          ::close(fd);
          return s;
        }
      } else if (errno == EEXIST) {  // created meanwhile by another opener
        fd = ::open(path.c_str(), O_RDWR | O_CLOEXEC);
      }
    }
    if (fd < 0) return LastErrnoStatus("cannot open", path);
    return std::make_unique<PosixRandomAccessFile>(fd, path);
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

bool IsTempFileName(absl::string_view file_name) {
  constexpr absl::string_view kInfix = ".tmp-";
  constexpr size_t kSuffix = 6;
  if (file_name.size() < 1 + kInfix.size() + kSuffix) return false;
  const size_t infix_at = file_name.size() - kSuffix - kInfix.size();
  if (file_name.substr(infix_at, kInfix.size()) != kInfix) return false;
  for (const char c : file_name.substr(file_name.size() - kSuffix)) {
    if (!absl::ascii_isalnum(static_cast<unsigned char>(c))) return false;
  }
  return true;
}

absl::Status CheckReplaceable(const std::string& path) {
  struct stat info;
  if (::lstat(path.c_str(), &info) != 0) {
    if (errno == ENOENT || errno == ENOTDIR) return absl::OkStatus();  // a new path
    return LastErrnoStatus("cannot inspect", path);
  }
  if (S_ISREG(info.st_mode)) return absl::OkStatus();
  const char* what = S_ISDIR(info.st_mode)    ? "a folder"
                     : S_ISLNK(info.st_mode)  ? "a symbolic link (name the file it points to)"
                     : S_ISCHR(info.st_mode)  ? "a character device"
                     : S_ISBLK(info.st_mode)  ? "a block device"
                     : S_ISFIFO(info.st_mode) ? "a FIFO"
                     : S_ISSOCK(info.st_mode) ? "a socket"
                                              : "not a regular file";
  return absl::FailedPreconditionError(
      absl::StrCat(path, " is ", what, ": only a regular file or a new path can be written"));
}

}  // namespace pdsm
