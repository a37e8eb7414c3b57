#include "core/assets/asset_store.h"

#include <fcntl.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <filesystem>
#include <system_error>

#include "absl/strings/escaping.h"
#include "absl/strings/str_cat.h"
#include "core/assets/mesh_asset.h"

namespace pdsm {
namespace {

absl::Status ErrnoStatus(int error_number, absl::string_view message) {
  return error_number != 0 ? absl::ErrnoToStatus(error_number, message)
                           : absl::UnknownError(message);
}

// For messages: a hash as the client sent it, escaped and cut short.
std::string Quoted(const std::string& text) {
  constexpr size_t kMax = 80;
  return absl::StrCat("\"", absl::CEscape(text.substr(0, kMax)), text.size() > kMax ? "..." : "",
                      "\"");
}

absl::Status CheckHash(const std::string& sha256) {
  if (IsSha256Hex(sha256)) return absl::OkStatus();
  return absl::InvalidArgumentError(
      absl::StrCat("asset ", Quoted(sha256), ": not a SHA-256 (64 lowercase hex digits)"));
}

// Syncs a folder, so that an entry renamed or created in it survives a crash.
absl::Status SyncDir(const std::string& dir) {
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return ErrnoStatus(errno, absl::StrCat("cannot open folder ", dir, " to sync it"));
  absl::Status status;
  if (::fsync(fd) != 0) status = ErrnoStatus(errno, absl::StrCat("cannot sync folder ", dir));
  ::close(fd);
  return status;
}

// Writes all of `bytes` to `fd` and syncs it to the disk.
absl::Status WriteSynced(int fd, std::string_view bytes, const std::string& path) {
  while (!bytes.empty()) {
    const ssize_t written = ::write(fd, bytes.data(), bytes.size());
    if (written < 0) {
      if (errno == EINTR) continue;
      return ErrnoStatus(errno, absl::StrCat("cannot write ", path));
    }
    bytes.remove_prefix(static_cast<size_t>(written));
  }
  // Before the rename: a crash must not leave a renamed file with missing bytes.
  if (::fsync(fd) != 0) return ErrnoStatus(errno, absl::StrCat("cannot sync ", path));
  return absl::OkStatus();
}

// Reads the whole open file, whose size fstat gave as `size`.
absl::StatusOr<std::string> ReadAll(int fd, size_t size, const std::string& path) {
  std::string bytes(size, '\0');
  size_t done = 0;
  while (done < size) {
    const ssize_t got = ::read(fd, bytes.data() + done, size - done);
    if (got < 0) {
      if (errno == EINTR) continue;
      return ErrnoStatus(errno, absl::StrCat("cannot read ", path));
    }
    if (got == 0) break;  // shorter than fstat said: the hash check reports it
    done += static_cast<size_t>(got);
  }
  bytes.resize(done);
  return bytes;
}

}  // namespace

absl::StatusOr<std::unique_ptr<AssetStore>> AssetStore::Open(const std::string& dir) {
  if (dir.empty()) return absl::InvalidArgumentError("asset store: the folder name is empty");
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) {
    return ErrnoStatus(ec.value(),
                       absl::StrCat("cannot create asset store folder ", dir, ": ", ec.message()));
  }
  if (!std::filesystem::is_directory(dir, ec)) {
    return absl::FailedPreconditionError(
        absl::StrCat("asset store ", dir, ": exists and is not a folder"));
  }
  return std::unique_ptr<AssetStore>(new AssetStore(dir));
}

std::string AssetStore::PathFor(const std::string& sha256) const {
  return (std::filesystem::path(dir_) / sha256.substr(0, 2) / sha256).string();
}

bool AssetStore::Has(const std::string& sha256) const {
  if (!IsSha256Hex(sha256)) return false;
  struct stat info;
  return ::stat(PathFor(sha256).c_str(), &info) == 0 && S_ISREG(info.st_mode);
}

absl::Status AssetStore::Put(const std::string& sha256, std::string_view bytes) {
  if (absl::Status s = CheckHash(sha256); !s.ok()) return s;
  const std::string actual = Sha256Hex(bytes);
  if (actual != sha256) {
    return absl::InvalidArgumentError(
        absl::StrCat("asset ", sha256, ": content hashes to ", actual));
  }

  const std::string shard = (std::filesystem::path(dir_) / sha256.substr(0, 2)).string();
  std::error_code ec;
  const bool created_shard = std::filesystem::create_directories(shard, ec);
  if (ec) {
    return ErrnoStatus(ec.value(), absl::StrCat("asset ", sha256, ": cannot create folder ", shard,
                                                ": ", ec.message()));
  }
  // mkostemp creates the file exclusively under a fresh name: concurrent writers of the same
  // blob, in threads or processes, never share a temporary file.
  std::string temp = absl::StrCat(shard, "/.", sha256, ".tmp-XXXXXX");
  const int fd = ::mkostemp(temp.data(), O_CLOEXEC);
  if (fd < 0) {
    return ErrnoStatus(errno, absl::StrCat("asset ", sha256, ": cannot create a file in ", shard));
  }
  absl::Status status = WriteSynced(fd, bytes, temp);
  if (::close(fd) != 0 && status.ok()) {
    status = ErrnoStatus(errno, absl::StrCat("cannot close ", temp));
  }
  const std::string path = PathFor(sha256);
  // rename() replaces an existing blob atomically; a reader sees the old file or the new one,
  // both complete and with the same bytes.
  if (status.ok() && std::rename(temp.c_str(), path.c_str()) != 0) {
    status = ErrnoStatus(errno, absl::StrCat("cannot rename ", temp, " to ", path));
  }
  if (!status.ok()) {
    ::unlink(temp.c_str());
    return status;
  }
  if (absl::Status s = SyncDir(shard); !s.ok()) return s;
  if (created_shard) return SyncDir(dir_);
  return absl::OkStatus();
}

absl::StatusOr<std::string> AssetStore::Get(const std::string& sha256) const {
  if (absl::Status s = CheckHash(sha256); !s.ok()) return s;
  const std::string path = PathFor(sha256);
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) {
    const int error_number = errno;
    if (error_number == ENOENT) {
      return absl::NotFoundError(absl::StrCat("asset ", sha256, ": not in the store"));
    }
    return ErrnoStatus(error_number, absl::StrCat("asset ", sha256, ": cannot open ", path));
  }
  struct stat opened;
  if (::fstat(fd, &opened) != 0) {
    const int error_number = errno;
    ::close(fd);
    return ErrnoStatus(error_number, absl::StrCat("asset ", sha256, ": cannot stat ", path));
  }
  if (!S_ISREG(opened.st_mode)) {
    ::close(fd);
    return absl::DataLossError(absl::StrCat("asset ", sha256, ": ", path, " is not a file"));
  }
  absl::StatusOr<std::string> bytes = ReadAll(fd, static_cast<size_t>(opened.st_size), path);
  ::close(fd);
  if (!bytes.ok()) return bytes.status();

  const std::string actual = Sha256Hex(*bytes);
  if (actual == sha256) return bytes;
  // Remove the corrupt file so that the next upload replaces it, but only if it is still the
  // file that was read: a concurrent Put may have renamed a good copy over it meanwhile.
  struct stat now;
  if (::stat(path.c_str(), &now) == 0 && now.st_dev == opened.st_dev &&
      now.st_ino == opened.st_ino) {
    ::unlink(path.c_str());
  }
  return absl::DataLossError(absl::StrCat("asset ", sha256, ": the stored content (", bytes->size(),
                                          " bytes) hashes to ", actual,
                                          "; removed the corrupt file ", path));
}

}  // namespace pdsm
