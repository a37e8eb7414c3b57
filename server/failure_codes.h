// The status codes a worker may report a task failure with (ReportFailureRequest.code): every
// absl/gRPC code but OK, in numeric order. What the workers service parses and what the
// coordinator's metrics label failures by, so both always know the same set.
#ifndef PDSM_SERVER_FAILURE_CODES_H_
#define PDSM_SERVER_FAILURE_CODES_H_

#include <array>

#include "absl/status/status.h"

namespace pdsm {

inline constexpr std::array<absl::StatusCode, 16> kFailureCodes = {
    absl::StatusCode::kCancelled,          absl::StatusCode::kUnknown,
    absl::StatusCode::kInvalidArgument,    absl::StatusCode::kDeadlineExceeded,
    absl::StatusCode::kNotFound,           absl::StatusCode::kAlreadyExists,
    absl::StatusCode::kPermissionDenied,   absl::StatusCode::kResourceExhausted,
    absl::StatusCode::kFailedPrecondition, absl::StatusCode::kAborted,
    absl::StatusCode::kOutOfRange,         absl::StatusCode::kUnimplemented,
    absl::StatusCode::kInternal,           absl::StatusCode::kUnavailable,
    absl::StatusCode::kDataLoss,           absl::StatusCode::kUnauthenticated};

}  // namespace pdsm

#endif  // PDSM_SERVER_FAILURE_CODES_H_
