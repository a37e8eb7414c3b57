// The coordinator's logic behind both gRPC services (jobs_service.h, workers_service.h): jobs
// and their state on disk, assets, scheduling, tile assembly and the final PDSM. The services
// only translate messages and check callers; everything here speaks absl::Status.
//
// On disk under data_dir: jobs.db (SQLite, job_store.h), assets/ (asset_store.h), and per job
// jobs/<id>/tiles/<index>.tile (assembled tiles, tile_file.h) then jobs/<id>/pdsm.exr. A tile
// is durable once its row is in jobs.db; the PDSM is written from the tile files when every
// tile is, so a restart resumes each unfinished job with only its missing tiles.
//
// Thread-safe. Heavy work (tile assembly, the final file) runs on an internal pool, never on
// the caller's thread, except SubmitBake's scene validation and planning.
#ifndef PDSM_SERVER_COORDINATOR_H_
#define PDSM_SERVER_COORDINATOR_H_

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "absl/status/statusor.h"
#include "core/assets/asset_store.h"
#include "core/bake/bake_plan.h"
#include "core/events/event.h"
#include "pdsm/v1/jobs.pb.h"
#include "pdsm/v1/workers.pb.h"
#include "server/job_store.h"
#include "core/pipeline/scheduler.h"

namespace pdsm {

struct CoordinatorOptions {
  std::string data_dir;
  int samples_per_task = 64;      // light samples per task (a tile's batch)
  int64_t lease_ms = 30'000;
  int max_open_tiles = 64;        // bounds the memory of partial results
  int max_task_failures = 3;
  int max_worker_failures = 3;
  int assembly_threads = 1;
  // Admission limits (RESOURCE_EXHAUSTED above them).
  int64_t max_job_pixels = int64_t{8192} * 8192;
  int max_samples = 65536;
  int64_t max_triangles = 20'000'000;
  int64_t max_asset_bytes = int64_t{1} << 30;
};

class Coordinator {
 public:
  // Opens (or creates) the data dir and resumes every unfinished job found there.
  static absl::StatusOr<std::unique_ptr<Coordinator>> Start(const CoordinatorOptions& options);
  ~Coordinator();  // stops the pool and the ticker; unfinished work stays on disk

  // ---- Job API ----
  std::vector<std::string> FindMissingAssets(const std::vector<std::string>& sha256) const;
  // Stores a complete blob. INVALID_ARGUMENT (bad hash or content), RESOURCE_EXHAUSTED (size).
  absl::Status PutAsset(const std::string& sha256, std::string_view bytes);
  int64_t max_asset_bytes() const { return options_.max_asset_bytes; }
  absl::StatusOr<pdsm::v1::Job> SubmitBake(const pdsm::v1::SubmitBakeRequest& request);
  absl::StatusOr<pdsm::v1::Job> GetJob(const std::string& job_id);
  absl::StatusOr<std::vector<pdsm::v1::Job>> ListJobs(int limit);
  absl::StatusOr<pdsm::v1::Job> CancelJob(const std::string& job_id);
  // The finished file. FAILED_PRECONDITION unless the job SUCCEEDED.
  absl::StatusOr<std::string> PdsmPath(const std::string& job_id);
  // A running (or queued) job's assembled tiles so far, ascending, and one tile's file.
  // FAILED_PRECONDITION once the job has ended; NOT_FOUND for an unknown job, or a tile index
  // out of the grid or not assembled yet.
  absl::StatusOr<std::vector<int>> FinishedTiles(const std::string& job_id);
  absl::StatusOr<std::string> FinishedTilePath(const std::string& job_id, int tile_index);
  absl::StatusOr<std::vector<double>> Query(const std::string& job_id,
                                            const std::vector<glm::dvec3>& points_world);
  pdsm::v1::Stats GetStats();

  // ---- Worker API ----
  std::optional<pdsm::v1::Task> LeaseTask(const std::string& worker_id);
  absl::StatusOr<int64_t> ExtendLease(const std::string& worker_id, uint64_t lease_id);
  // False when the result was dropped (late, duplicate, job gone). INVALID_ARGUMENT when the
  // events do not fit the task's tile.
  absl::StatusOr<bool> ReportResult(const std::string& worker_id, uint64_t lease_id,
                                    const pdsm::v1::TileEventsData& events);
  void ReportFailure(const std::string& worker_id, uint64_t lease_id, const std::string& reason,
                     bool handed_back);
  absl::StatusOr<pdsm::v1::GetJobSceneResponse> JobScene(const std::string& job_id);
  absl::StatusOr<std::string> GetAsset(const std::string& sha256) const;

 private:
  struct ActiveJob;
  explicit Coordinator(const CoordinatorOptions& options);
  absl::Status Resume();
  // `plan`: the job's plan when the caller has it (a new job); else planned from the record.
  absl::Status Activate(const JobRecord& record, const std::vector<int>& done_tiles,
                        std::optional<BakePlan> plan);
  absl::StatusOr<std::shared_ptr<ActiveJob>> LoadActive(const JobRecord& record,
                                                        std::optional<BakePlan> plan);
  absl::StatusOr<BakePlan> PlanFromScene(const pdsm::v1::Scene& scene, const std::string& label,
                                         bool enforce_limits) const;
  pdsm::v1::Job ToProto(const JobRecord& record) const;
  // `tile_samples` > 0: an adaptive tile baked with that many samples; 0: a fixed-count one.
  void AssembleAndStore(std::shared_ptr<ActiveJob> job, int tile_index,
                        std::vector<std::pair<int, TileEvents>> parts, int tile_samples);
  // Adaptive jobs: after a tile's stage, assemble the tile or queue its next stage
  // (docs/algorithms.md section 9).
  void JudgeStage(std::shared_ptr<ActiveJob> job, int tile_index,
                  std::vector<std::pair<int, TileEvents>> parts);
  void FinishJob(std::shared_ptr<ActiveJob> job);
  void EndJob(const std::string& job_id, pdsm::v1::JobState state, const std::string& error);
  void Post(std::function<void()> work);
  void PoolLoop();
  void TickLoop();
  std::string JobDir(const std::string& job_id) const;
  std::string TilesDir(const std::string& job_id) const;
  std::string TilePath(const std::string& job_id, int tile_index) const;
  int64_t NowMs() const;

  const CoordinatorOptions options_;
  std::unique_ptr<JobStore> store_;
  std::unique_ptr<AssetStore> assets_;

  std::mutex mu_;  // guards everything below up to pool_mu_
  Scheduler scheduler_;
  std::map<std::string, std::shared_ptr<ActiveJob>> active_;
  std::deque<std::pair<int64_t, int64_t>> recent_results_;  // (time ms, events), last 60 s
  int64_t started_ms_ = 0;
  bool stopping_ = false;
  std::condition_variable tick_cv_;

  std::mutex pool_mu_;
  std::condition_variable pool_cv_;
  std::deque<std::function<void()>> pool_queue_;
  bool pool_stopping_ = false;
  std::vector<std::thread> pool_;
  std::thread ticker_;

  std::mutex query_mu_;  // the last queried PDSM, kept for repeated queries
  std::string query_job_;
  std::shared_ptr<const struct PdsmImage> query_image_;
};

}  // namespace pdsm

#endif  // PDSM_SERVER_COORDINATOR_H_
