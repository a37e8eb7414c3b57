// What every binary prints for --version (pdsm, pdsm-coordinator, pdsm-worker, pdsm-view): the
// project's version (CMake's project(VERSION)) and the newest PDSM file format the build reads
// and writes (kPdsmFormatVersion; a bake that needs no newer feature is written as an older
// one), the two things a bug report or a mixed-version farm needs to know.
#ifndef PDSM_CORE_UTIL_VERSION_H_
#define PDSM_CORE_UTIL_VERSION_H_

#include <string>

#include "absl/strings/string_view.h"

namespace pdsm {

// The project version, e.g. "0.1.0".
absl::string_view ProjectVersion();

// "<program> <version> (PDSM file format <n>)", no newline.
std::string VersionLine(absl::string_view program);

}  // namespace pdsm

#endif  // PDSM_CORE_UTIL_VERSION_H_
