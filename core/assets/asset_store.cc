#include "core/assets/asset_store.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <filesystem>
#include <system_error>

#include "absl/strings/escaping.h"
#include "absl/strings/str_cat.h"
#include "core/assets/mesh_asset.h"
#include "core/util/atomic_file.h"

namespace pdsm {
namespace {

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

// Reads the whole open file, whose size fstat gave as `size`.
absl::StatusOr<std::string> ReadAll(int fd, size_t size, const std::string& path) {
  std::string bytes(size, '\0');
  size_t done = 0;
  while (done < size) {
    const ssize_t got = ::read(fd, bytes.data() + done, size - done);
    if (got < 0) {
      const int error_number = errno;
      if (error_number == EINTR) continue;
      return ErrnoStatus(error_number, absl::StrCat("cannot read ", path));
    }
    if (got == 0) break;  // shorter than fstat said: the hash check reports it
    done += static_cast<size_t>(got);
  }
  bytes.resize(done);
  return bytes;
}

}  // namespace

absl::StatusOr<std::unique_ptr<AssetStore>> AssetStore::Open(const std::string& dir,
                                                             FileSystem* fs) {
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
  return std::unique_ptr<AssetStore>(new AssetStore(dir, fs ? fs : FileSystem::Default()));
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
  // A unique temporary name: concurrent writers of the same blob, in threads or processes,
  // never share a temporary file; rename() replaces an existing blob atomically, so a reader
  // sees the old file or the new one, both complete and with the same bytes.
  const absl::string_view contents(bytes.data(), bytes.size());
  if (absl::Status s = WriteFileAtomically(PathFor(sha256), contents, fs_); !s.ok()) {
    return absl::Status(s.code(), absl::StrCat("asset ", sha256, ": ", s.message()));
  }
  // A new shard is an entry of the store's folder: durable once that is synced too.
  if (created_shard) return fs_->SyncDir(dir_);
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
