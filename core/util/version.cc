#include "core/util/version.h"

#include "absl/strings/str_cat.h"
#include "core/bake/plan_fingerprint.h"
#include "core/pdsm/pdsm_image.h"

namespace pdsm {

// PDSM_VERSION and PDSM_GIT_COMMIT are defined for this file only (core/CMakeLists.txt): a
// new version or commit rebuilds one file, not every file that includes a header.
absl::string_view ProjectVersion() { return PDSM_VERSION; }

absl::string_view GitCommit() { return PDSM_GIT_COMMIT; }

std::string VersionLine(absl::string_view program) {
  return absl::StrCat(program, " ", ProjectVersion(), " (commit ", GitCommit(),
                      "; PDSM file format 1-", kPdsmFormatVersion, "; plan fingerprint schema ",
                      kPlanFingerprintSchema, ")");
}

}  // namespace pdsm
