// The coordinator's logic behind both gRPC services (jobs_service.h, workers_service.h). The
// services only translate messages and check callers; everything here speaks absl::Status.
// It is the bake engine (core/pipeline/bake_engine.h, the same one the local bake runs) plus
// what a service needs around it, each in its own file:
//   job_admission.h      what a submitted job must satisfy, planning within the limits
//   job_store.h          job state in SQLite (jobs.db), so jobs survive a restart
//   stored_job.h         where a running job's tiles and PDSM go (DATA_DIR/jobs/<id>/)
//   coordinator_assets.h uploaded mesh blobs (DATA_DIR/assets/)
//   query_cache.h        the PDSM QueryAttenuation reads
//   plan_budget.h        which jobs hold their plans in memory, which wait for it
// On start every unfinished job found in the data dir resumes with only its missing tiles.
//
// Thread-safe. Heavy work (tile assembly, the final file) runs on an internal pool, never on
// the caller's thread; scene validation and planning of a submit run on an admission thread
// of their own (SubmitBakeAsync), one submit at a time, so that a large submit neither
// blocks a gRPC thread nor runs beside another one.
#ifndef PDSM_SERVER_COORDINATOR_H_
#define PDSM_SERVER_COORDINATOR_H_

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "absl/base/thread_annotations.h"
#include "absl/status/statusor.h"
#include "absl/synchronization/mutex.h"
#include "absl/synchronization/notification.h"
#include "core/events/event.h"
#include "core/pipeline/bake_engine.h"
#include "core/util/file_system.h"
#include "core/util/work_queue.h"
#include "metrics/histogram.h"
#include "pdsm/v1/jobs.pb.h"
#include "pdsm/v1/workers.pb.h"
#include "server/coordinator_assets.h"
#include "server/coordinator_metrics.h"
#include "server/job_admission.h"
#include "server/job_lights.h"
#include "server/job_store.h"
#include "server/plan_budget.h"
#include "server/query_cache.h"
#include "server/stored_job.h"

namespace pdsm {

inline constexpr double kDefaultVerifyFraction = 0.02;

struct CoordinatorOptions {
  std::string data_dir;
  // Light samples per task (a group's batch). 0: the job's samples / 8, within [1, 64], so
  // that even a one-group job is at least 8 tasks the farm's workers share.
  int samples_per_task = 0;
  int64_t lease_ms = 30'000;
  // Tiles whose partial results may be open at once (at least one group is, however large).
  // 4096 since 2026-12-06: at 64, any group of more than 64 tiles (a sun over a world: groups
  // of hundreds or thousands of tiles) ran alone, one after the other, while workers idled
  // between them; 4096 open tiles cost the coordinator no measurable memory (docs/service.md).
  int max_open_tiles = 4096;
  // Partial results (running event lists) held in memory before they move to a scratch file
  // in data_dir (core/pipeline/event_spill.h). Changes no byte of any PDSM.
  int64_t event_memory_budget_bytes = kDefaultEventMemoryBudget;
  // QueryAttenuation's tiles kept in memory (core/pdsm/pdsm_tile_cache.h).
  int64_t query_cache_bytes = kDefaultTileCacheBytes;
  int max_task_failures = 3;
  int max_worker_failures = 3;
  // Verification by redundancy (core/pipeline/scheduler.h): this fraction of tasks, drawn at
  // random, is run by a second worker and compared bit for bit; a worker outvoted two to one
  // is quarantined and what it fed is recomputed. 0 turns it off. The farm's extra work is the
  // fraction (2 % by default).
  double verify_fraction = kDefaultVerifyFraction;
  uint64_t verify_seed = 0;  // 0: unpredictable; tests fix it
  int assembly_threads = 1;
  AdmissionLimits limits;  // RESOURCE_EXHAUSTED above them
  int64_t max_asset_bytes = int64_t{1} << 30;
  // Where tiles, PDSMs and assets are written; null: the real file system. (jobs.db is
  // SQLite's own.)
  FileSystem* fs = nullptr;
};

class Coordinator {
 public:
  // Opens (or creates) the data dir and resumes every unfinished job found there.
  static absl::StatusOr<std::unique_ptr<Coordinator>> Start(const CoordinatorOptions& options);
  ~Coordinator();  // stops the pool and the ticker; unfinished work stays on disk

  // ---- Job API ----
  CoordinatorAssets& assets() { return *assets_; }
  absl::StatusOr<pdsm::v1::Job> SubmitBake(const pdsm::v1::SubmitBakeRequest& request);
  // SubmitBake on the admission thread; `done` is called there with its result, exactly once
  // (also when the coordinator is being destroyed: queued submits run before it stops).
  // `request` must outlive the call of `done`.
  void SubmitBakeAsync(const pdsm::v1::SubmitBakeRequest* request,
                       std::function<void(absl::StatusOr<pdsm::v1::Job>)> done);
  absl::StatusOr<pdsm::v1::Job> GetJob(const std::string& job_id);
  absl::StatusOr<std::vector<pdsm::v1::Job>> ListJobs(int limit);
  absl::StatusOr<pdsm::v1::Job> CancelJob(const std::string& job_id);
  // The finished file. FAILED_PRECONDITION unless the job SUCCEEDED.
  absl::StatusOr<std::string> PdsmPath(const std::string& job_id);
  // A running (or queued) job's assembled tiles of one light so far (the light's own tile
  // indices), ascending, and one tile's file. `light`: a light's name, "" for a one-light job
  // (errors as FindJobLight's, server/job_lights.h). FAILED_PRECONDITION once the job has
  // ended; NOT_FOUND for an unknown job or a tile not assembled yet; INVALID_ARGUMENT for a
  // tile index outside the light's [0, tiles_total).
  absl::StatusOr<std::vector<int>> FinishedTiles(const std::string& job_id,
                                                 std::string_view light = {});
  // The tile's bytes: a tile file (core/pipeline/tile_file.h).
  absl::StatusOr<std::string> FinishedTileBytes(const std::string& job_id, std::string_view light,
                                                int tile_index);
  // The attenuation at each point of the finished job's light `light` ("" every light): as
  // QueryCache::Query.
  absl::StatusOr<QueryAnswer> Query(const std::string& job_id, std::string_view light,
                                    const std::vector<glm::dvec3>& points_world);
  pdsm::v1::Stats GetStats();
  // Everything /metrics shows (server/coordinator_metrics.h). Thread-safe.
  CoordinatorMetrics Metrics();

  // ---- Worker API ----
  std::optional<pdsm::v1::Task> LeaseTask(const std::string& worker_id);
  // Verification outvoted the worker: it gets no task again (WorkersService answers its
  // LeaseTask PERMISSION_DENIED, so that a pdsm-worker exits saying why).
  bool Quarantined(const std::string& worker_id) { return engine_.Quarantined(worker_id); }
  // The lease's length in ms. FAILED_PRECONDITION when the lease is not current.
  absl::StatusOr<int64_t> ExtendLease(const std::string& worker_id, uint64_t lease_id);
  // `tiles`: one per tile of the task, in its order. False when the result was dropped (late,
  // duplicate, job gone). INVALID_ARGUMENT when there are not as many as the task's tiles or
  // one does not fit its tile.
  // `seconds`: the worker's time on the task (finite, >= 0), for the task-seconds metric.
  absl::StatusOr<bool> ReportResult(
      const std::string& worker_id, uint64_t lease_id,
      const google::protobuf::RepeatedPtrField<pdsm::v1::TileEventsData>& tiles, double seconds);
  // `incompatible`: the worker plans the job differently (BakeEngine::ReportIncompatible);
  // logged once per (job, worker).
  // `failure`: the worker's reason (message) and code (counted by code in the metrics).
  void ReportFailure(const std::string& worker_id, uint64_t lease_id, const absl::Status& failure,
                     bool handed_back, bool incompatible);
  // The worker is leaving: no longer counted active.
  void SignOff(const std::string& worker_id);
  // FAILED_PRECONDITION when the job is not running.
  absl::StatusOr<pdsm::v1::GetJobSceneResponse> JobScene(const std::string& job_id);
  // The refined pixels of the light named `light` ("" for a one-light job) as its running
  // refinement level bakes them (core/bake/refined_pixels_codec.h): FetchRefinement's.
  // FAILED_PRECONDITION when the job is not running or the light has no level running; the
  // errors of FindJobLight.
  absl::StatusOr<std::shared_ptr<const std::string>> RefinedPixelsBlob(const std::string& job_id,
                                                                       const std::string& light);

 private:
  explicit Coordinator(const CoordinatorOptions& options);
  // Every unfinished job of the data dir waits its turn (budget_), and the turns that fit
  // are taken at once.
  absl::Status Resume();
  // Hands the job's lights to the engine, one engine job each (server/job_lights.h).
  // `plans`: the job's plans (counted in budget_). `done_tiles`: the job's (not a light's)
  // tiles stored already, ascending.
  absl::Status Activate(const JobRecord& record, const std::vector<int>& done_tiles,
                        std::vector<PlannedLight> plans);
  // Activate for a job budget_ counts as activating; then cancels it if a cancel came
  // meanwhile. On failure the job holds nothing.
  absl::Status ActivateCounted(const JobRecord& record, const std::vector<int>& done_tiles,
                               std::vector<PlannedLight> plans);
  // Plans and activates waiting jobs while their turns fit (PlanBudget::TakeNext). A job that
  // cannot be planned or activated FAILS (its error says why); the others go on. On the
  // admission thread (or in Start, before it serves).
  void ActivateWaiting();
  // Records a job that never ran as ended (CANCELLED or FAILED) with `why`.
  void EndUnstarted(const std::string& job_id, pdsm::v1::JobState state, const absl::Status& why);
  // Cancels the job's lights in the engine (a cancel by request).
  void CancelRunning(const std::string& job_id);
  // Ends every light of the job still in the engine as failed with `why`.
  void EndLights(const std::string& job_id, const absl::Status& why);
  std::shared_ptr<StoredJob> Active(const std::string& job_id) const;
  // Light samples per task for an engine job of `plan` (--samples-per-task, or an eighth of
  // its samples within [1, 64]).
  int SamplesPerTask(const BakePlan& plan) const;
  // The job when it is running here; else FAILED_PRECONDITION saying its state (NOT_FOUND
  // for no such job).
  absl::StatusOr<std::shared_ptr<StoredJob>> RunningJob(const std::string& job_id);
  // Each light's progress: the engine's while its engine job runs, the light's last after
  // it ended; nullopt for neither (the whole job ended meanwhile).
  std::vector<std::optional<JobProgress>> LightsProgress(const StoredJob& job) const;
  // The lights' progress summed (nullopt when none has any): the job's.
  static std::optional<JobProgress> SumProgress(
      const std::vector<std::optional<JobProgress>>& lights);
  // Job.lights, and for an ended job of several lights its samples_done over their samples.
  // `active`: the job when it runs here (for the fingerprints); `progress`: LightsProgress of
  // it, empty when it does not run.
  // Returns the running refinement levels' ETAs (server/job_eta.h).
  std::vector<double> AddLightsProgress(const JobRecord& record,
                                        const std::vector<JobLightSize>& sizes,
                                        const StoredJob* active,
                                        const std::vector<std::optional<JobProgress>>& progress,
                                        pdsm::v1::Job* job) const;
  // Adds the active jobs to *started (with a task leased) or *waiting, and to *progress (if
  // not null) their done fraction.
  void CountActiveJobs(int* started, int* waiting,
                       std::vector<std::pair<std::string, double>>* progress) const;
  void Forget(const std::string& job_id);
  // The job as the API shows it: the stored record, with the engine's progress while it runs.
  pdsm::v1::Job ToProto(const JobRecord& record) const;
  void TickUntilStopped();

  const CoordinatorOptions options_;
  std::unique_ptr<JobStore> store_;
  std::unique_ptr<CoordinatorAssets> assets_;
  QueryCache query_cache_;
  const int64_t started_ms_;

  BakeEngine engine_;
  Histogram task_seconds_{SecondsBuckets()};  // of accepted results
  mutable absl::Mutex mu_;
  std::map<std::string, std::shared_ptr<StoredJob>> active_ ABSL_GUARDED_BY(mu_);
  // Which jobs hold their plans, which wait for memory (--max-planned-mib). Every job of
  // active_ is counted in it, from before its activation to Forget.
  PlanBudget budget_;
  absl::Notification stopping_;
  // Declared last: destroyed (stopped, joined) first, while what its work uses still exists.
  // Runs the ticker and the engine's heavy work.
  WorkQueue pool_;
  // Submits, one at a time; drained (not dropped) by the destructor, which answers them.
  WorkQueue admission_{1};
};

}  // namespace pdsm

#endif  // PDSM_SERVER_COORDINATOR_H_
