// A fingerprint of a bake plan: SHA-256 over every number that decides the output bytes
// (header, samples, lattice, clips, tiles, light-space casters). The coordinator sends it
// with each task; a worker whose own plan differs (another build, another libm) refuses the
// task instead of silently breaking the "same input, same bytes" promise.
#ifndef PDSM_CORE_BAKE_PLAN_FINGERPRINT_H_
#define PDSM_CORE_BAKE_PLAN_FINGERPRINT_H_

#include <string>

#include "core/bake/bake_plan.h"

namespace pdsm {

// Which numbers the fingerprint covers, and how they are fed; hashed first, so builds of
// different schemas never agree by accident. Bump it when PlanFingerprint changes what it
// feeds (--version prints it).
inline constexpr int kPlanFingerprintSchema = 1;

// Lowercase hex, 64 characters.
std::string PlanFingerprint(const BakePlan& plan);

}  // namespace pdsm

#endif  // PDSM_CORE_BAKE_PLAN_FINGERPRINT_H_
