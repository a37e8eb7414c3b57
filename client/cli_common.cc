#include "client/cli_common.h"

#include <cstdio>

#include "absl/strings/str_format.h"

namespace pdsm {

int ExitCodeFor(const absl::Status& status) {
  switch (status.code()) {
    case absl::StatusCode::kOk:
      return kExitOk;
    case absl::StatusCode::kInvalidArgument:
    case absl::StatusCode::kNotFound:
    case absl::StatusCode::kDataLoss:
    case absl::StatusCode::kFailedPrecondition:
    case absl::StatusCode::kOutOfRange:
    case absl::StatusCode::kResourceExhausted:
      return kExitBadInput;
    default:
      return kExitFailure;
  }
}

int ReportError(const absl::Status& status) {
  std::fprintf(stderr, "pdsm: %s\n", std::string(status.message()).c_str());
  return ExitCodeFor(status);
}

std::string LightsText(size_t lights, size_t parts) {
  if (lights == parts) return absl::StrFormat("%d lights", lights);
  return absl::StrFormat("%d %s in %d parts", lights, lights == 1 ? "light" : "lights", parts);
}

}  // namespace pdsm
