// Which bakes the coordinator takes: a submitted request's own fields checked, its scene
// loaded from the uploaded assets and planned, within the coordinator's limits
// (RESOURCE_EXHAUSTED above them, naming the field). A resumed job is planned the same way
// without the limits: it was admitted once.
#ifndef PDSM_SERVER_JOB_ADMISSION_H_
#define PDSM_SERVER_JOB_ADMISSION_H_

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "core/bake/bake_plan.h"
#include "core/bake/refined_pixels.h"
#include "core/scene/scene.h"
#include "pdsm/v1/jobs.pb.h"
#include "server/coordinator_assets.h"
#include "server/job_lights.h"
#include "server/job_store.h"

namespace pdsm {

// 4 GiB. Most jobs hold little (the 10^6-triangle village of 55 lights 0.4 MiB, a job of 2^18
// tiles 0.1 MiB); what is large is a surfaces-only bake's receivers, ~24 bytes a triangle per
// light (that village surfaces-only: ~1.3 GiB), and meshes inline in the scene.
inline constexpr int64_t kDefaultMaxPlannedBytes = int64_t{4096} << 20;

struct AdmissionLimits {
  // A map's memory no longer grows with its pixels (tiles are written as they finish, and an
  // all-lit tile costs a few bytes: docs/performance.md, "Maps of any size"), so the default
  // is the scene format's own limit; its tiles are what max_job_tiles bounds.
  int64_t max_job_pixels = kMaxPdsmPixels;
  // Tiles are the unit of the plan, the job store and the tile files: checked before the plan
  // is made, so that a 1 KB request cannot make the coordinator plan 67 million tiles (8192^2
  // at tile size 1 took 87 s and 5 GB). 2^18 is 8192^2 at tile size 16, 32768^2 at 64.
  int64_t max_job_tiles = int64_t{1} << 18;
  int max_samples = 65536;
  int64_t max_triangles = 20'000'000;
  // What the plans of all the jobs the coordinator runs may hold (JobHeldBytes): a job whose
  // plans alone exceed it is refused (PlanJobLights); one that does not fit beside the running
  // jobs' waits (server/plan_budget.h).
  int64_t max_planned_bytes = kDefaultMaxPlannedBytes;
};

// INVALID_ARGUMENT naming the field: the idempotency key (1 to 128 printable ASCII
// characters, no spaces) or the priority (within [-1000, 1000]).
absl::Status CheckSubmitRequest(const pdsm::v1::SubmitBakeRequest& request);

// Loads `scene` (meshes from `assets`) and plans each of its lights as the local bake does
// (the scene baking that light alone), in scene order; `label` prefixes errors. `limits`
// null: none are checked; else each light within them, and before anything is planned the
// tiles of all the lights together within max_job_tiles (the job store's unit) and a lower
// bound of JobHeldBytes (core/bake/plan_memory.h) within max_planned_bytes, then, as the
// lights are planned, JobHeldBytes itself. Each plan is fingerprinted and then
// released of its render geometry as soon as it is made, so that planning a world of many
// lights never holds more than one light's geometry besides the scene.
absl::StatusOr<std::vector<PlannedLight>> PlanJobLights(const pdsm::v1::Scene& scene,
                                                        const std::string& label,
                                                        const CoordinatorAssets& assets,
                                                        const AdmissionLimits* limits);

// The refinement level of light `light` of `scene` (adaptive resolution, docs/algorithms.md
// section 10) for the pixels `refined` chosen from its base map `base` (PlanJobLights'),
// planned as the local bake and the workers plan it (PlanRefinementLevel), fingerprinted and
// released as PlanJobLights' lights are. Its memory is not counted against the planned-bytes
// budget (docs/service.md says so). Errors: loading the scene, planning the level.
absl::StatusOr<PlannedLight> PlanJobLightLevel(const pdsm::v1::Scene& scene,
                                               const std::string& label,
                                               const CoordinatorAssets& assets, int light,
                                               const BakePlan& base,
                                               std::shared_ptr<const RefinedPixels> refined);

// What one light's plan, or a refinement level's (its refined pixels included), and its
// engine job hold in the coordinator: JobHeldBytes of one plan, without the scene.
int64_t LightHeldBytes(const BakePlan& plan);

// What a job of these plans holds in the coordinator while it runs, in bytes: its plans
// (core/bake/plan_memory.h), the engine's records of their groups (BakeEngine::JobHeldBytes)
// and its scene, parsed and serialized. What --max-planned-mib counts.
int64_t JobHeldBytes(const std::vector<PlannedLight>& plans, const pdsm::v1::Scene& scene);

// The record of a new job: a fresh random id, QUEUED, its tiles and samples summed over the
// lights (`plans`, one per light in scene order; width, height and samples the first's), the
// scene serialized.
absl::StatusOr<JobRecord> NewJobRecord(const pdsm::v1::SubmitBakeRequest& request,
                                       const std::vector<PlannedLight>& plans, int64_t now_unix_ms);

// Each light of a job's stored scene, in scene order, as its plan sizes it, with its effective
// bake settings (EffectiveBakeParams, core/scene/scene_loader.h), read from the serialized
// bytes without parsing the meshes (no planning). DATA_LOSS when the bytes are not a scene;
// INVALID_ARGUMENT (prefixed with `label`) for bake fields the loader refuses.
struct JobLightSize {
  std::string name;  // "" for the light of a one-light scene that has none
  int width = 0, height = 0, samples = 0;
  int tiles = 0;              // of its tile grid
  pdsm::v1::BakeParams bake;  // its effective bake settings (EffectiveBakeParams)
};
absl::StatusOr<std::vector<JobLightSize>> JobLightSizes(const std::string& serialized_scene,
                                                        const std::string& label);

// `bytes` random bytes in lowercase hex (std::random_device).
std::string RandomHex(int bytes);

}  // namespace pdsm

#endif  // PDSM_SERVER_JOB_ADMISSION_H_
