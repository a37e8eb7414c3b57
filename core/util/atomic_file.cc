#include "core/util/atomic_file.h"

#include <fcntl.h>
#include <stdlib.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <vector>

#include "absl/strings/str_cat.h"

namespace pdsm {
namespace {

// Writes all of `contents` to `fd` and syncs it; false (errno set) on failure.
bool WriteAllSynced(int fd, absl::string_view contents) {
  while (!contents.empty()) {
    const ssize_t n = ::write(fd, contents.data(), contents.size());
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    contents.remove_prefix(static_cast<size_t>(n));
  }
  return ::fsync(fd) == 0;
}

}  // namespace

absl::Status WriteFileAtomically(const std::string& path, absl::string_view contents) {
  // mkstemp: a fresh name (O_EXCL) beside the target, so concurrent writers never share one.
  std::string pattern = path + ".tmp-XXXXXX";
  std::vector<char> name(pattern.begin(), pattern.end());
  name.push_back('\0');
  const int fd = ::mkstemp(name.data());
  if (fd < 0) {
    return absl::InvalidArgumentError(
        absl::StrCat("cannot write \"", path, "\": ", std::strerror(errno)));
  }
  const std::string temp(name.data());
  absl::Status status;
  if (!WriteAllSynced(fd, contents)) {
    status = absl::InternalError(absl::StrCat("writing \"", temp, "\": ", std::strerror(errno)));
  }
  if (::close(fd) != 0 && status.ok()) {
    status = absl::InternalError(absl::StrCat("closing \"", temp, "\": ", std::strerror(errno)));
  }
  std::error_code ec;
  if (status.ok()) {
    std::filesystem::rename(temp, path, ec);
    if (ec) status = absl::InternalError(absl::StrCat("\"", path, "\": ", ec.message()));
  }
  if (!status.ok()) std::filesystem::remove(temp, ec);
  return status;
}

}  // namespace pdsm
