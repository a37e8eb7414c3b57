// What both services check in a request before the coordinator sees it, and how text a caller
// sent may appear in a log line: ids bounded and of a known alphabet (an error that names
// them stays short: a 1,000,000-character job_id used to come back whole in the status, past
// what clients accept as metadata), and free text escaped (a newline in a worker's reason
// used to write a forged line into the coordinator's log).
#ifndef PDSM_SERVER_REQUEST_CHECKS_H_
#define PDSM_SERVER_REQUEST_CHECKS_H_

#include <cstddef>
#include <string>
#include "absl/strings/string_view.h"

#include "absl/status/status.h"

namespace pdsm {

inline constexpr size_t kMaxJobIdBytes = 64;
inline constexpr size_t kMaxWorkerIdBytes = 256;
// What a worker's failure reason keeps (workers.proto: "at most 4 KiB is kept").
inline constexpr size_t kMaxReasonBytes = 4096;

// INVALID_ARGUMENT "job_id: ..." unless `id` has 1 to kMaxJobIdBytes characters of
// [0-9A-Za-z_-] (the coordinator's ids are 16 hex digits). The message does not repeat it.
absl::Status CheckJobId(absl::string_view id);

// INVALID_ARGUMENT "light: ..." unless `name` is empty or what a scene's light name may be
// (docs/scene_format.md): 1 to 64 characters of [A-Za-z0-9_.-], or a sphere light's face, that
// name and "@+x" (core/scene/sphere_faces.h). The message does not repeat it.
absl::Status CheckLightName(absl::string_view name);

// INVALID_ARGUMENT "worker_id: ..." unless `id` has 1 to kMaxWorkerIdBytes printable ASCII
// characters (pdsm-worker sends host-pid-suffix): it is logged and counted as given.
absl::Status CheckWorkerId(absl::string_view id);

// `text` made safe for one log line or status message: backslash, control characters and
// bytes outside printable ASCII C-escaped (\n, \x1b, …), then cut to `max_bytes` with
// "…(N bytes)" appended when longer.
std::string Printable(absl::string_view text, size_t max_bytes);

}  // namespace pdsm

#endif  // PDSM_SERVER_REQUEST_CHECKS_H_
