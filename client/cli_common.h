// Shared pieces of the `pdsm` subcommands: exit codes, error printing, and how a file's lights
// are counted in what they print.
#ifndef PDSM_CLIENT_CLI_COMMON_H_
#define PDSM_CLIENT_CLI_COMMON_H_

#include <cstddef>
#include <string>

#include "absl/status/status.h"

namespace pdsm {

inline constexpr int kExitOk = 0;
inline constexpr int kExitFailure = 1;
inline constexpr int kExitBadInput = 2;

// Bad input (the user can fix it: a field, a file, a flag) exits 2; anything else 1.
int ExitCodeFor(const absl::Status& status);

// Prints "pdsm: <message>" on stderr and returns ExitCodeFor(status).
int ReportError(const absl::Status& status);

// "3 lights", or "1 light in 6 parts" when a sphere's faces (core/scene/sphere_faces.h) make
// more parts than lights: `pdsm bake`'s and `pdsm info`'s wording.
std::string LightsText(size_t lights, size_t parts);

}  // namespace pdsm

#endif  // PDSM_CLIENT_CLI_COMMON_H_
