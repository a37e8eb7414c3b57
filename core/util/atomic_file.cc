#include "core/util/atomic_file.h"

#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "absl/strings/str_cat.h"

namespace pdsm {

absl::Status WriteFileAtomically(const std::string& path, absl::string_view contents) {
  // The pid keeps two processes writing the same target from sharing a temporary file.
  const std::string temp = absl::StrCat(path, ".tmp-", getpid());
  absl::Status status;
  {
    std::ofstream out(temp, std::ios::binary | std::ios::trunc);
    if (!out) return absl::InvalidArgumentError(absl::StrCat("cannot write \"", path, "\""));
    out.write(contents.data(), static_cast<std::streamsize>(contents.size()));
    out.flush();
    if (!out) status = absl::InternalError(absl::StrCat("writing \"", temp, "\" failed"));
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
