// A running job's ETA (GetJob's and WatchJob's eta_seconds): each part's estimate from its own
// rate so far, and the job's from its parts: its lights' base maps, counted together, and each
// refinement level that runs (docs/service.md, "Adaptive resolution"). A level's work is known
// only once its light's base map is baked, so a level yet to come is in no estimate.
//
// Pure functions of their arguments: seconds, never negative but for < 0 meaning "unknown".
#ifndef PDSM_SERVER_JOB_ETA_H_
#define PDSM_SERVER_JOB_ETA_H_

#include <cstdint>
#include <span>

#include "core/pipeline/bake_engine.h"

namespace pdsm {

// Seconds left of an engine job's samples at the rate it has gained them since it was added
// (JobProgress::samples_at_add, added_ms) to `now_ms` (the engine's clock): 0 when none is
// left, < 0 while nothing was gained yet.
double RateEtaSeconds(const JobProgress& progress, int64_t now_ms);

// The job's: the longest of its parts', as they share the workers (one light's level alone:
// exactly its own). `base`: its base maps' estimate, ignored once `base_done`; `levels`: each
// running level's. Unknown (< 0) while any part that still runs has no estimate.
double JobEtaSeconds(double base, bool base_done, std::span<const double> levels);

}  // namespace pdsm

#endif  // PDSM_SERVER_JOB_ETA_H_
