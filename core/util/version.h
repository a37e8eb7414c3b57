// What every binary prints for --version (pdsm, pdsm-coordinator, pdsm-worker, pdsm-view): the
// project's version (CMake's project(VERSION)), the git commit of the build, the PDSM file
// formats it reads (1 to kPdsmFormatVersion; a bake that needs no newer feature is written as
// an older one) and the plan-fingerprint schema (core/bake/plan_fingerprint.h): what a bug
// report or a mixed-version farm needs to know. Workers and coordinators of one schema and
// commit plan alike; others may, and the fingerprint decides per job.
#ifndef PDSM_CORE_UTIL_VERSION_H_
#define PDSM_CORE_UTIL_VERSION_H_

#include <string>

#include "absl/strings/string_view.h"

namespace pdsm {

// The project version, e.g. "0.1.0".
absl::string_view ProjectVersion();

// The git commit the build was configured from: 12 hex digits, or "unknown".
absl::string_view GitCommit();

// "<program> <version> (commit <c>; PDSM file format 1-<n>; plan fingerprint schema <s>)",
// no newline.
std::string VersionLine(absl::string_view program);

}  // namespace pdsm

#endif  // PDSM_CORE_UTIL_VERSION_H_
