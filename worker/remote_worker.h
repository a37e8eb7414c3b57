// pdsm-worker's main loop: N threads of a WorkQueue, each with its own OSMesa context, pull
// tasks from the coordinator, run them (bake_task.h) and report the events. A lease keeper thread
// extends the leases of running tasks; a lost lease (expired, cancelled job) stops its task at the
// next light sample. Scenes and mesh assets are fetched once per job and cached on disk by
// content hash.
#ifndef PDSM_WORKER_REMOTE_WORKER_H_
#define PDSM_WORKER_REMOTE_WORKER_H_

#include <atomic>
#include <map>
#include <memory>
#include <string>
#include <tuple>
#include <utility>

#include "absl/base/thread_annotations.h"
#include "absl/status/status.h"
#include "absl/synchronization/mutex.h"
#include "core/assets/asset_store.h"
#include "core/bake/bake_plan.h"
#include "core/scene/scene.h"
#include "worker/coordinator_client.h"
#include "worker/group_cache.h"
#include "worker/worker_metrics.h"

namespace pdsm {

struct RemoteWorkerOptions {
  int threads = 1;
  std::string cache_dir;  // mesh assets by SHA-256
  // Tests only (pdsm-worker's hidden --test-only-fingerprint-salt): appended to this worker's
  // plan fingerprints, so that it plans every job "differently", as another build would.
  std::string test_fingerprint_salt;
};

class RemoteWorker {
 public:
  // `client` must outlive the worker.
  static absl::StatusOr<std::unique_ptr<RemoteWorker>> Create(CoordinatorClient* client,
                                                              const RemoteWorkerOptions& options);
  ~RemoteWorker();

  // Runs until `stop` becomes true; tasks in flight then are handed back undone and the
  // worker signs off. Returns OK after a clean stop. Errors no retry can mend end it within
  // one call: UNAUTHENTICATED or PERMISSION_DENIED (a wrong token) and UNIMPLEMENTED (a
  // coordinator without this API) come back as that status, its message saying what to fix.
  // Others (UNAVAILABLE, deadlines) are retried with capped exponential backoff and jitter.
  // A job whose plan this build computes differently is reported incompatible (not a
  // failure) and the worker goes on with other jobs.
  absl::Status Run(const std::atomic<bool>& stop);

  // Its tasks so far (for /metrics); safe to read while Run runs.
  const WorkerMetrics& metrics() const { return metrics_; }

 private:
  struct JobContext {
    BakePlan plan;
    std::string fingerprint;
    std::unique_ptr<GroupCache> groups;  // of `plan`, shared by the threads on this job
  };
  struct RunningLease {
    std::atomic<bool> lost{false};
  };

  RemoteWorker(CoordinatorClient* client, const RemoteWorkerOptions& options,
               std::unique_ptr<AssetStore> assets)
      : client_(client), options_(options), assets_(std::move(assets)) {}

  void ThreadLoop(const std::atomic<bool>& stop);
  void KeepLeases(const std::atomic<bool>& stop);
  // True when `status` is permanent (see Run): records the first such error and stops every
  // thread.
  bool StopIfPermanent(const absl::Status& status);
  bool Stopping(const std::atomic<bool>& stop) const { return stop || fatal_stop_; }
  // The plan of the job's light `light` (Task.light: "" for a one-light job), or with `level`
  // of its refinement level (Task.refinement_level: PlanRefinementLevel of the light's plan and
  // the refined pixels FetchRefinement returns), planned here on first use from the job's
  // scene (fetched once per job: JobScene).
  using JobKey = std::tuple<std::string, std::string, bool>;  // (job id, light, level)
  absl::StatusOr<std::shared_ptr<const JobContext>> Context(const JobKey& key);
  absl::StatusOr<std::shared_ptr<const JobContext>> LoadContext(const JobKey& key)
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(jobs_mu_);
  // The job's scene and the index its lights are planned through (the index refers to the
  // scene, which it keeps alive with it).
  struct JobWorld {
    std::shared_ptr<const Scene> scene;
    std::shared_ptr<const SceneIndex> index;
  };
  absl::StatusOr<JobWorld> JobScene(const std::string& job_id)
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(jobs_mu_);

  CoordinatorClient* client_;
  const RemoteWorkerOptions options_;
  std::unique_ptr<AssetStore> assets_;

  absl::Mutex jobs_mu_;  // held while a job's context loads: one download per job
  std::map<JobKey, std::shared_ptr<const JobContext>> jobs_ ABSL_GUARDED_BY(jobs_mu_);
  // The scene of the job planned last (its lights are planned one by one as tasks come).
  std::string scene_job_ ABSL_GUARDED_BY(jobs_mu_);
  JobWorld world_ ABSL_GUARDED_BY(jobs_mu_);

  WorkerMetrics metrics_;
  std::atomic<bool> fatal_stop_{false};
  absl::Mutex fatal_mu_;
  absl::Status fatal_ ABSL_GUARDED_BY(fatal_mu_);

  absl::Mutex leases_mu_;
  std::map<uint64_t, std::shared_ptr<RunningLease>> leases_ ABSL_GUARDED_BY(leases_mu_);
  int64_t lease_ms_ ABSL_GUARDED_BY(leases_mu_) = 30'000;  // the coordinator's, latest task
};

}  // namespace pdsm

#endif  // PDSM_WORKER_REMOTE_WORKER_H_
