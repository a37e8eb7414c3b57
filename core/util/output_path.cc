#include "core/util/output_path.h"

#include <sys/stat.h>

#include <filesystem>
#include <system_error>

#include "absl/strings/str_cat.h"
#include "core/util/file_system.h"

namespace pdsm {

absl::Status CheckOutputPath(absl::string_view flag, const std::string& path,
                             const std::vector<std::string>& inputs) {
  if (path.empty()) return absl::InvalidArgumentError(absl::StrCat(flag, ": the path is empty"));
  if (absl::Status s = CheckReplaceable(path); !s.ok()) {
    return absl::InvalidArgumentError(absl::StrCat(flag, " ", s.message()));
  }
  struct stat output;
  if (::stat(path.c_str(), &output) != 0) return absl::OkStatus();  // a new path
  for (const std::string& input : inputs) {
    struct stat in;
    if (input.empty() || input == "-" || ::stat(input.c_str(), &in) != 0) continue;
    if (in.st_dev == output.st_dev && in.st_ino == output.st_ino) {
      return absl::InvalidArgumentError(absl::StrCat(
          flag, " ", path, " is ", input, ", an input of this command: it would be replaced"));
    }
  }
  return absl::OkStatus();
}

absl::Status CheckOutputPaths(const OutputPaths& outputs, const std::vector<std::string>& inputs) {
  std::vector<std::pair<std::string, std::filesystem::path>> seen;
  for (const auto& [flag, path] : outputs) {
    if (path.empty()) continue;
    if (absl::Status s = CheckOutputPath(flag, path, inputs); !s.ok()) return s;
    std::error_code ec;
    const std::filesystem::path normal = std::filesystem::weakly_canonical(path, ec);
    if (ec) continue;
    for (const auto& [other_flag, other] : seen) {
      if (other == normal) {
        return absl::InvalidArgumentError(
            absl::StrCat(flag, " ", path, ": the same file as ", other_flag,
                         " (two outputs cannot share a path: give one of them another)"));
      }
    }
    seen.emplace_back(flag, normal);
  }
  return absl::OkStatus();
}

}  // namespace pdsm
