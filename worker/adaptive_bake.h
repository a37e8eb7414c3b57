// The local bake of an adaptive plan (core/bake/adaptive_sampling.h): tiles are baked in
// stages of doubling sample ranges, and a tile's next stage is queued only once its previous
// stages are merged and judged not converged. Same output bytes whatever the threads and
// samples_per_task, like the fixed-count bake.
#ifndef PDSM_WORKER_ADAPTIVE_BAKE_H_
#define PDSM_WORKER_ADAPTIVE_BAKE_H_

#include "absl/status/statusor.h"
#include "worker/local_bake.h"
#include "core/bake/bake_plan.h"
#include "core/pdsm/pdsm_file.h"

namespace pdsm {

// REQUIRES: plan.header.adaptive(). Writes every tile to `writer` (not Finish()) and the
// preview when options.preview_path is set. `threads` >= 1.
absl::StatusOr<BakeSummary> RunAdaptiveTiles(const BakePlan& plan, const LocalBakeOptions& options,
                                             int threads, PdsmWriter* writer);

}  // namespace pdsm

#endif  // PDSM_WORKER_ADAPTIVE_BAKE_H_
