// Shared pieces of the `pdsm` subcommands: exit codes and error printing.
#ifndef PDSM_CLIENT_CLI_COMMON_H_
#define PDSM_CLIENT_CLI_COMMON_H_

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

}  // namespace pdsm

#endif  // PDSM_CLIENT_CLI_COMMON_H_
