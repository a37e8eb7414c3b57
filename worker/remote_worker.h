// pdsm-worker's main loop: N threads, each with its own OSMesa context, pull tasks from the
// coordinator, run them (bake_task.h) and report the events. A lease keeper thread extends
// the leases of running tasks; a lost lease (expired, cancelled job) stops its task at the
// next light sample. Scenes and mesh assets are fetched once per job and cached on disk by
// content hash.
#ifndef PDSM_WORKER_REMOTE_WORKER_H_
#define PDSM_WORKER_REMOTE_WORKER_H_

#include <atomic>
#include <map>
#include <memory>
#include <mutex>
#include <string>

#include "absl/status/status.h"
#include "core/assets/asset_store.h"
#include "core/bake/bake_plan.h"
#include "worker/coordinator_client.h"

namespace pdsm {

struct RemoteWorkerOptions {
  int threads = 1;
  std::string cache_dir;  // mesh assets by SHA-256
};

class RemoteWorker {
 public:
  // `client` must outlive the worker.
  static absl::StatusOr<std::unique_ptr<RemoteWorker>> Create(CoordinatorClient* client,
                                                              const RemoteWorkerOptions& options);
  ~RemoteWorker();

  // Runs until `stop` becomes true; tasks in flight then are handed back undone. Returns OK
  // after a clean stop.
  absl::Status Run(const std::atomic<bool>& stop);

 private:
  struct JobContext {
    BakePlan plan;
    std::string fingerprint;
  };
  struct RunningLease {
    std::atomic<bool> lost{false};
  };

  RemoteWorker(CoordinatorClient* client, const RemoteWorkerOptions& options,
               std::unique_ptr<AssetStore> assets)
      : client_(client), options_(options), assets_(std::move(assets)) {}

  void ThreadLoop(const std::atomic<bool>& stop);
  void KeepLeases(const std::atomic<bool>& stop);
  absl::StatusOr<std::shared_ptr<const JobContext>> Context(const std::string& job_id);
  absl::StatusOr<std::shared_ptr<const JobContext>> LoadContext(const std::string& job_id);

  CoordinatorClient* client_;
  const RemoteWorkerOptions options_;
  std::unique_ptr<AssetStore> assets_;

  std::mutex jobs_mu_;  // held while a job's context loads: one download per job
  std::map<std::string, std::shared_ptr<const JobContext>> jobs_;

  std::mutex leases_mu_;
  std::map<uint64_t, std::shared_ptr<RunningLease>> leases_;
  int64_t lease_ms_ = 30'000;  // the coordinator's, from the latest task
};

}  // namespace pdsm

#endif  // PDSM_WORKER_REMOTE_WORKER_H_
