// Writing a whole file so that readers see the old file or the new one, never half of one:
// the bytes go to a fresh temporary name beside the target (mkstemp), are synced, and the
// temporary file is renamed onto the target.
#ifndef PDSM_CORE_UTIL_ATOMIC_FILE_H_
#define PDSM_CORE_UTIL_ATOMIC_FILE_H_

#include <string>

#include "absl/status/status.h"
#include "absl/strings/string_view.h"

namespace pdsm {

// INVALID_ARGUMENT naming `path` when its folder cannot be written, INTERNAL when writing or
// renaming fails; the temporary file is removed on failure and `path` is left as it was.
absl::Status WriteFileAtomically(const std::string& path, absl::string_view contents);

}  // namespace pdsm

#endif  // PDSM_CORE_UTIL_ATOMIC_FILE_H_
