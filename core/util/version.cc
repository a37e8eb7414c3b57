#include "core/util/version.h"

#include "absl/strings/str_cat.h"
#include "core/pdsm/pdsm_image.h"

namespace pdsm {

// PDSM_VERSION is defined for this file only (core/CMakeLists.txt): a new version rebuilds
// one file, not every file that includes a header.
absl::string_view ProjectVersion() { return PDSM_VERSION; }

std::string VersionLine(absl::string_view program) {
  return absl::StrCat(program, " ", ProjectVersion(), " (PDSM file format ", kPdsmFormatVersion,
                      ")");
}

}  // namespace pdsm
