// The lights of a coordinator's job, as the bake engine runs them. Each light of the scene is
// planned as the local bake plans it (the scene baking that light alone: ForLight,
// core/scene/scene.h) and runs as an engine job of its own (core/pipeline/bake_engine.h), so
// that every light keeps its own samples, batches and adaptive stages, and the lights' tasks
// share the one queue: they all have the job's priority and submission order, and the engine
// ids keep them in scene order among themselves.
//
// Numbering. The job's tiles, for the job store and the tile files (server/stored_job.h), are
// its lights' tiles one after another in scene order: tile t of light i is the job's tile
// lights[i].tile_offset + t. A one-light job's tiles and engine id are those of the job, as
// they were before scenes had several lights.
#ifndef PDSM_SERVER_JOB_LIGHTS_H_
#define PDSM_SERVER_JOB_LIGHTS_H_

#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/statusor.h"
#include "core/bake/bake_plan.h"

namespace pdsm {

// A light as the coordinator plans it (PlanJobLights): the plan without what only a worker's
// renderer uses (ReleaseRenderGeometry), and the fingerprint of the whole plan, taken before
// (what a worker's own plan of the light must match).
struct PlannedLight {
  std::shared_ptr<const BakePlan> plan;
  std::string fingerprint;
};

struct JobLight {
  int index = 0;     // in the scene
  std::string name;  // Light.name; "" only for the light of a one-light scene
  std::shared_ptr<const BakePlan> plan;
  std::string fingerprint;  // PlanFingerprint of the whole plan (PlannedLight)
  int tile_offset = 0;      // its first tile's index among the job's tiles
  std::string engine_id;    // EngineJobId(job_id, index, light count)
  int tile_count() const { return plan->tile_count(); }
};

// The job's lights from their plans (one per light, in scene order). REQUIRES: non-empty.
std::vector<JobLight> MakeJobLights(const std::string& job_id, std::vector<PlannedLight> plans);

// The engine job of light `light` of `light_count`: the job id for a one-light job, else
// "<job id>/<light, 5 digits>" ('/' is in neither a job id nor a light name; the digits sort
// in scene order).
std::string EngineJobId(const std::string& job_id, int light, int light_count);

// The engine job of the refinement level of the light whose engine job is `light_engine_id`
// (adaptive resolution, docs/algorithms.md section 10): "<light's engine id>/refined".
std::string LevelEngineJobId(const std::string& light_engine_id);

// The job and light of an engine job id (light 0 for a bare job id), and whether it is the
// light's refinement level; nullopt for an id EngineJobId or LevelEngineJobId cannot have made.
struct EngineJobOf {
  std::string job_id;
  int light = 0;
  bool level = false;
};
std::optional<EngineJobOf> ParseEngineJobId(std::string_view engine_id);

// The light named `name` among `lights`, as PdsmReader::FindLight selects a file's part:
// "" is the job's only light (FAILED_PRECONDITION naming the lights when it has several);
// NOT_FOUND naming the lights for a name that is none of them. `job_id` labels the errors.
absl::StatusOr<int> FindJobLight(const std::vector<JobLight>& lights, std::string_view name,
                                 const std::string& job_id);

}  // namespace pdsm

#endif  // PDSM_SERVER_JOB_LIGHTS_H_
