// The scheduling state machine of every bake: which task a worker gets next, leases and their
// deadlines, failures, exclusions, cancellation. Pure logic with an explicit clock (`now_ms`),
// so tests drive it with a fake clock. Not thread-safe: core/pipeline/bake_engine.h owns one
// and calls it under its mutex, for the coordinator's remote workers and the local bake's
// threads alike.
//
// A job's work is its tiles x sample batches. Tasks are handed out tile by tile: at most
// `max_open_tiles` tiles (over all jobs) have work issued but are not yet assembled, which is
// what bounds the coordinator's memory whatever the job size. Jobs run by priority (higher
// first), then in submission order. Adaptive jobs hand out a tile's work in stages: the next
// stage's batches are queued only when the service calls AddStage().
#ifndef PDSM_CORE_PIPELINE_SCHEDULER_H_
#define PDSM_CORE_PIPELINE_SCHEDULER_H_

#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "absl/status/statusor.h"

namespace pdsm {

struct SchedulerOptions {
  int64_t lease_ms = 30'000;            // a lease lasts this long unless extended
  int max_task_failures = 3;            // distinct workers a task may fail on; then the job fails
  int max_worker_failures_per_job = 3;  // failures after which a worker gets no more of a job
  int max_open_tiles = 64;              // tiles with issued, unassembled work, over all jobs
  int64_t worker_active_ms = 30'000;    // a worker is active if seen this recently
  uint64_t lease_id_base = 1;           // first lease id; a restarted coordinator picks a new
                                        // base so results for its predecessor's leases drop
};

struct JobSpec {
  std::string job_id;
  int priority = 0;
  int64_t sequence = 0;      // submission order, ascending
  std::vector<int> tiles;    // tiles still to do (a resumed job lists only unfinished ones)
  int samples = 1;           // light samples of the bake
  int samples_per_task = 1;  // batch size; the last batch of a tile may be smaller
  // Adaptive sampling (core/bake/adaptive_sampling.h): > 0 makes a tile's work come in stages
  // of these first samples; after each stage completes the service either assembles the tile
  // or calls AddStage(). 0: one stage holding all `samples`.
  int adaptive_min_samples = 0;
};

struct TaskLease {
  uint64_t lease_id = 0;
  std::string job_id;
  int tile_index = 0;
  int sample_begin = 0, sample_end = 0;
  int64_t deadline_ms = 0;
};

// What happened to a reported result.
struct ResultOutcome {
  enum Kind { kDropped, kAccepted, kTileComplete } kind = kDropped;
  std::string job_id;  // set unless dropped
  int tile_index = 0;
  int sample_begin = 0, sample_end = 0;
};

struct JobFailure {
  std::string job_id;
  std::string reason;
};

struct SchedulerStats {
  int tasks_pending = 0;
  int tasks_leased = 0;
  int tiles_open = 0;
  int workers_active = 0;
  int64_t leases_expired = 0;
  int64_t results_dropped = 0;
  int64_t results_accepted = 0;
};

class Scheduler {
 public:
  explicit Scheduler(SchedulerOptions options);

  // REQUIRES: job_id not already present. A job with no tiles is complete at once.
  void AddJob(const JobSpec& job);

  // The next task for `worker_id`, or nullopt when none may be issued now. Records the worker
  // as seen. Never gives a worker a task of a job it is excluded from, nor a task it failed.
  std::optional<TaskLease> Lease(const std::string& worker_id, int64_t now_ms);

  // New deadline. FAILED_PRECONDITION when the lease is not current or not this worker's.
  absl::StatusOr<int64_t> Extend(const std::string& worker_id, uint64_t lease_id, int64_t now_ms);

  // Accepts the result of a current lease held by `worker_id`; anything else is dropped
  // (late after expiry, duplicate, cancelled job, unknown lease). kTileComplete: every batch
  // of that tile is now accepted and it awaits TileAssembled(). A lease expires when Tick()
  // finds its deadline passed; until then it is current. Extend, Complete and Fail also record
  // the worker as seen (a worker busy on a long task is active).
  ResultOutcome Complete(const std::string& worker_id, uint64_t lease_id, int64_t now_ms);

  // The worker could not do the task. Unless `handed_back`, it counts against the worker and
  // the task; the task goes back to the queue. Returns the job's failure when the task has now
  // failed on max_task_failures distinct workers (the job is then removed).
  std::optional<JobFailure> Fail(const std::string& worker_id, uint64_t lease_id,
                                 const std::string& reason, bool handed_back, int64_t now_ms);

  // Re-queues tasks whose lease has expired (a failure of their holder: a dead or stalled
  // worker) and fails jobs that can no longer progress: a task failed on too many workers, or
  // every active worker excluded. Call periodically.
  std::vector<JobFailure> Tick(int64_t now_ms);

  // Adaptive jobs: queues the next stage of a tile whose stage just completed (kTileComplete)
  // instead of assembling it. Returns false, changing nothing, for an unknown job or tile, a
  // tile with work outstanding, a fixed-count job, or a tile past its last stage.
  bool AddStage(const std::string& job_id, int tile_index);

  // Frees the tile's slot after the service has stored it.
  // REQUIRES: Complete() returned kTileComplete for it.
  void TileAssembled(const std::string& job_id, int tile_index);

  // True when every tile of the job is assembled (the job then leaves the scheduler after
  // RemoveJob). False for unknown jobs.
  bool JobComplete(const std::string& job_id) const;

  // Forgets the job: its pending tasks vanish, its current leases become stale (their results
  // are dropped, their extensions refused). Used for cancel, failure and completion.
  void RemoveJob(const std::string& job_id);

  // The current lease `lease_id` (any worker's), or nullopt. Lets the service check a result
  // against its task before accepting it.
  std::optional<TaskLease> FindLease(uint64_t lease_id) const;

  bool HasJob(const std::string& job_id) const;
  // Tasks of the job not yet accepted, as far as they are known (an adaptive job's later
  // stages add theirs); nullopt for an unknown job.
  std::optional<int64_t> TasksLeft(const std::string& job_id) const;
  SchedulerStats Stats(int64_t now_ms) const;

 private:
  // A sample batch of an open tile.
  struct Task {
    int sample_begin = 0, sample_end = 0;
    bool done = false;
    std::optional<uint64_t> lease_id;  // set while leased
    // (worker, reason) of each failure; the workers are distinct since a task never goes back
    // to a worker it failed on.
    std::vector<std::pair<std::string, std::string>> failures;
  };
  // A tile from its opening until TileAssembled(). Unopened tiles are only entries of
  // Job::tile_order, so a job's memory follows its open tiles, not its size.
  struct Tile {
    int position = 0;         // in Job::tile_order
    int stage = 0;            // adaptive jobs: the stage whose tasks are the last of `tasks`
    std::vector<Task> tasks;  // by batch
    int tasks_left = 0;
  };
  // Scheduling order: priority desc, then sequence asc (job id breaks ties).
  struct JobKey {
    int priority = 0;
    int64_t sequence = 0;
    std::string job_id;
    bool operator<(const JobKey& o) const;
  };
  // (position of the tile in Job::tile_order, batch): sorted, it is the order tasks go out.
  using TaskRef = std::pair<int, int>;
  struct Job {
    JobKey key;
    int samples = 1;
    int samples_per_task = 1;
    int adaptive_min_samples = 0;  // 0: fixed-count job
    std::vector<int> tile_order;   // tiles in the order they open
    size_t next_tile = 0;          // next tile of tile_order to open
    std::map<int, Tile> tiles;     // open tiles by tile index
    std::set<TaskRef> pending;     // tasks of open tiles waiting for a worker
    std::set<uint64_t> leases;     // current leases
    int64_t tasks_left = 0;        // not yet accepted, open or not
    int tiles_left = 0;            // not yet assembled
    std::map<std::string, int> worker_failures;
    std::string last_failure;
  };
  struct LeaseInfo {
    std::string job_id;
    TaskRef task;
    std::string worker_id;
    int64_t deadline_ms = 0;
  };
  using LeaseMap = std::map<uint64_t, LeaseInfo>;

  std::optional<TaskLease> TryLease(Job& job, const std::string& worker_id, int64_t now_ms);
  bool OpenTile(Job& job);
  // The sample ranges of a tile's stage, cut into batches of samples_per_task.
  static std::vector<std::pair<int, int>> StageBatches(const Job& job, int stage);
  void AddTasks(Job& job, Tile& tile, int stage);
  TaskLease Issue(Job& job, TaskRef task, const std::string& worker_id, int64_t now_ms);
  Tile& TileOf(Job& job, TaskRef task);
  LeaseMap::iterator FindCurrent(const std::string& worker_id, uint64_t lease_id);
  LeaseInfo TakeLease(LeaseMap::iterator it);
  void Requeue(Job& job, TaskRef task);
  std::optional<JobFailure> FailTask(LeaseMap::iterator it, const std::string& reason,
                                     bool handed_back);
  std::optional<JobFailure> CountFailure(Job& job, TaskRef task, const std::string& worker_id,
                                         const std::string& reason);
  bool Excluded(const Job& job, const std::string& worker_id) const;
  bool FailedAllRemaining(const Job& job, const std::string& worker_id) const;
  std::optional<JobFailure> CheckStuck(const Job& job) const;
  void UpdateReady(const Job& job);
  void Touch(const std::string& worker_id, int64_t now_ms);
  void ForgetInactiveWorkers(int64_t now_ms);

  SchedulerOptions options_;
  uint64_t next_lease_id_;
  std::map<std::string, Job> jobs_;
  std::set<JobKey> order_;  // every job
  std::set<JobKey> ready_;  // jobs with pending tasks of open tiles
  LeaseMap leases_;
  std::set<std::pair<int64_t, uint64_t>> deadlines_;  // (deadline, lease id) of current leases
  std::map<std::string, int64_t> worker_seen_ms_;
  std::set<std::pair<int64_t, std::string>> workers_by_seen_;  // (last seen, worker)
  int tiles_open_ = 0;
  int64_t leases_expired_ = 0;
  int64_t results_dropped_ = 0;
  int64_t results_accepted_ = 0;
};

}  // namespace pdsm

#endif  // PDSM_CORE_PIPELINE_SCHEDULER_H_
