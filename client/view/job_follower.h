// Follows a bake job on the service for pdsm-view --server: while the job runs, the tiles
// finished so far (ListFinishedTiles, FetchTile), assembled into a PDSM whose unfinished
// pixels are marked pending; once it has succeeded, the whole file (FetchPdsm).
//
// The PDSM's geometry comes from planning the scene file locally with the job's own bake
// settings (GetJob's `bake`: every override of the submit, every default as the coordinator
// resolved it) through PlanBake, the coordinator's own planner: the same scene and settings
// give the same plan, which the job's plan fingerprint confirms.
#ifndef PDSM_CLIENT_VIEW_JOB_FOLLOWER_H_
#define PDSM_CLIENT_VIEW_JOB_FOLLOWER_H_

#include <atomic>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "absl/base/thread_annotations.h"
#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/synchronization/mutex.h"
#include "client/service/service_connection.h"
#include "core/bake/bake_plan.h"
#include "core/pdsm/pdsm_image.h"

namespace pdsm::view {

// A PDSM as far as it is known: pixels of unfinished tiles are empty functions and flagged.
struct PartialPdsm {
  PdsmImage image;
  std::vector<uint8_t> pending;  // per pixel, row-major; empty when the PDSM is complete
  bool complete() const { return pending.empty(); }
};

// The job now (GetJob).
absl::StatusOr<pdsm::v1::Job> FetchJob(const ServiceFlags& service, const std::string& job_id);

// The job's light named `light` (Job.lights), as the viewer selects it: "" is the job's only
// light. Null for a job that lists no lights (an older coordinator) when `light` is "";
// INVALID_ARGUMENT naming the job's lights when there is no such light or "" for several.
absl::StatusOr<const pdsm::v1::LightProgress*> FindJobLight(const pdsm::v1::Job& job,
                                                            const std::string& light);

// The scene file loaded with the bake settings of the job's light `light` (its
// LightProgress.bake, or Job.bake for a one-light job), so that planning that light gives the
// job's plan of it whatever was overridden at submit; the caller then takes that light
// (OneLight). A job from a coordinator that reports no settings (an older build) loads with
// the file's own, with a warning.
absl::StatusOr<Scene> LoadJobScene(const std::string& scene_path, const pdsm::v1::Job& job,
                                   const std::string& light);

// INVALID_ARGUMENT when the job reports a plan fingerprint for the light and `plan` has
// another one: the scene file is not the one the job was submitted from (or was edited
// since).
absl::Status CheckPlanMatchesJob(const BakePlan& plan, const pdsm::v1::Job& job,
                                 const std::string& light, const std::string& scene_path);

// The plan's header with every tile pending.
PartialPdsm EmptyPartialPdsm(const BakePlan& plan);
// Builds the image from the finished tiles (any subset of the plan's grid).
PartialPdsm AssemblePartialPdsm(const BakePlan& plan, const std::map<int, PdsmTile>& tiles);

struct JobSnapshot {
  pdsm::v1::Job job;
  std::optional<PartialPdsm> pdsm;  // set when it changed since the last snapshot
};

class JobFollower {
 public:
  // REQUIRES: `plan` is the plan of the job's light `light` ("" for a one-light job; see
  // above). Connects; Poll answers INVALID_ARGUMENT when the light's size or samples differ
  // from the plan's.
  static absl::StatusOr<std::unique_ptr<JobFollower>> Create(const ServiceFlags& service,
                                                             const std::string& job_id,
                                                             const std::string& light,
                                                             const BakePlan* plan);

  // One step: the job's state, and the PDSM if it gained tiles or finished. The final PDSM
  // is fetched once the job SUCCEEDED. FAILED_PRECONDITION when the job failed or was
  // cancelled; errors of the calls otherwise.
  absl::StatusOr<JobSnapshot> Poll();

  // Polls every `interval_ms` on a thread of its own until the job ends; Take() hands over
  // the newest snapshot (nullopt when nothing changed), and the error that stopped it.
  void Start(int interval_ms);
  std::optional<JobSnapshot> Take();
  absl::Status error();
  ~JobFollower();

 private:
  JobFollower(const ServiceFlags& service, const std::string& job_id, const std::string& light,
              const BakePlan* plan, ServiceConnection connection)
      : service_(service),
        job_id_(job_id),
        light_(light),
        plan_(plan),
        connection_(std::move(connection)) {}
  // One finished tile's file bytes (FetchTile).
  absl::StatusOr<std::string> FetchTileBytes(int tile_index);

  const ServiceFlags service_;
  const std::string job_id_;
  const std::string light_;
  const BakePlan* plan_;
  ServiceConnection connection_;
  std::map<int, PdsmTile> tiles_;  // Poll's own state (one caller at a time)
  bool finished_ = false;

  std::thread thread_;
  std::atomic<bool> stop_{false};
  absl::Mutex mu_;
  std::optional<JobSnapshot> latest_ ABSL_GUARDED_BY(mu_);
  absl::Status error_ ABSL_GUARDED_BY(mu_);
};

}  // namespace pdsm::view

#endif  // PDSM_CLIENT_VIEW_JOB_FOLLOWER_H_
