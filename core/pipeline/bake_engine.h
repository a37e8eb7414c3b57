// The bake as a service, in one piece of code: the jobs in progress, their tasks
// (scheduler.h: leases, retries, priorities, adaptive stages), the batches workers return,
// the stage rule (stage_rule.h), tile assembly (tile_assembly.h) and where finished tiles go
// (a JobOutput). The coordinator (server/) drives it from remote workers over gRPC; the local
// bake (worker/local_bake.h) from N task runners in one process. Same plan, same scheduler,
// same rule, same assembly: the same bytes, by construction.
//
//   AddJob ─► Lease ─► (a worker runs the task: a tile group, a batch of samples) ─► Report
//                ▲        each tile's events merged as they come; a group's stage complete:
//                │                                      ▼ (executor) JudgeStage, per tile
//                └──── next adaptive stage ◄── tiles not done ──┤
//                                              tiles done ─► AssemblePlanTile ─► StoreTile
//                                          every tile stored ─► Finish ─► Ended(kSucceeded)
//
// Thread-safe. Bookkeeping (Lease, Extend, Report, ReportFailure, Tick) holds one mutex
// briefly; heavy work (merging, judging, assembling, storing a tile, writing the file) goes
// through EngineOptions::executor and never runs under the mutex. JobOutput calls are made
// without the mutex held.
#ifndef PDSM_CORE_PIPELINE_BAKE_ENGINE_H_
#define PDSM_CORE_PIPELINE_BAKE_ENGINE_H_

#include <atomic>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "absl/base/thread_annotations.h"
#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/synchronization/mutex.h"
#include "absl/time/time.h"
#include "core/bake/bake_plan.h"
#include "core/events/event.h"
#include "core/pdsm/pdsm_image.h"
#include "core/pipeline/event_spill.h"
#include "core/pipeline/scheduler.h"
#include "core/pipeline/stage_rule.h"
#include "core/pipeline/tile_assembly.h"
#include "core/util/file_system.h"

namespace pdsm {

enum class JobEnd { kSucceeded, kFailed, kCancelled };

// EngineOptions::event_memory_budget_bytes unless set: small next to the fixed cost of a bake
// process (Mesa, LLVM, the scene: ~170 MiB for the dragon), so that its memory stays within
// 10 % of it whatever the samples; spilling costs ~1 % of the CPU (docs/performance.md).
inline constexpr int64_t kDefaultEventMemoryBudget = int64_t{8} << 20;

// Where a job stands. Samples are counted over tiles (a tile of n samples counts n).
struct JobProgress {
  bool started = false;  // a task has been leased
  int tiles_total = 0;
  int tiles_done = 0;
  int tiles_all_lit = 0;       // stored with no vertex at all (no caster reaches their rays)
  int tiles_without_task = 0;  // stored all lit without a task (plan.tile_has_casters)
  int64_t tasks_done = 0;      // accepted results
  int64_t tasks_total = 0;     // known so far: adaptive stages add theirs as tiles need them
  int64_t samples_total = 0;
  int64_t samples_done = 0;
  int64_t samples_at_add = 0;      // samples_done when AddJob ran (a resumed job starts > 0)
  int64_t added_ms = 0;            // now_ms() at AddJob: with the two above, this run's rate
  int64_t tile_samples_total = 0;  // samples behind the stored tiles (adaptive: < maximum)
  int64_t spilled_bytes = 0;       // running event lists moved to the scratch file
  int tiles_recomputed = 0;        // stored, then withdrawn because a quarantined worker fed them
  AssemblyStats assembly;          // of every assembly, recomputed tiles' included
};

// Where a job's results go: the local bake writes the PDSM as tiles come; the coordinator
// keeps each tile on disk and in its job store, then writes the PDSM from them.
class JobOutput {
 public:
  virtual ~JobOutput() = default;

  // The job's first task was leased. At most once, on the leasing thread.
  virtual void Started() {}
  // A finished tile. Once per tile, from the executor; different tiles may be stored at the
  // same time. An error fails the job.
  virtual absl::Status StoreTile(const PdsmTile& tile) = 0;
  // The tiles stored so far (StoreTile) must be durable before this returns: called from the
  // executor after each finished stage of a tile group has stored its tiles, before the group
  // counts as assembled, so that an output may make a whole stage durable at once (one sync,
  // one transaction) instead of each tile. Called as StoreTile is; an error fails the job. The
  // default does nothing (StoreTile was durable).
  virtual absl::Status CommitTiles() { return absl::OkStatus(); }
  // Tiles no caster reaches (core/pipeline/unreached_tile.h), in ascending batches, instead of
  // StoreTile for each: their content follows from `plan`. The default stores
  // MakeUnreachedTile of each through StoreTile; an output may record them without their
  // bytes. Called as StoreTile is; an error fails the job.
  virtual absl::Status StoreUnreachedTiles(const BakePlan& plan, const std::vector<int>& tiles);
  // Every tile is stored: produce the PDSM. Once, from the executor, unless the job ended
  // first. An error fails the job.
  virtual absl::Status Finish() = 0;
  // Verification by redundancy (SchedulerOptions::verify_fraction) found that these stored
  // tiles hold a quarantined worker's results: they will be stored again, recomputed, before
  // Finish; until then they are not done (a resumed job must redo them). From any thread
  // holding no engine lock; may race with the recomputed tile's StoreTile (the tile is then
  // redone once more after a restart, never lost). An error fails the job. The default refuses:
  // an output that cannot take a tile back must not be used with verification.
  virtual absl::Status WithdrawTiles(const std::vector<int>& tile_indices);
  // Exactly once, when the job leaves the engine: kSucceeded after Finish() returned OK,
  // kFailed with the reason, kCancelled with Cancel()'s status; `progress` as it was then.
  // Always after every Started, StoreTile and Finish call of the job has returned, and none
  // starts after it.
  virtual void Ended(JobEnd end, const absl::Status& status, const JobProgress& progress) = 0;
};

struct EngineOptions {
  SchedulerOptions scheduler;
  // Runs heavy work: inline on the reporting thread (the local bake, whose task threads are
  // the pool) or on a pool (the coordinator, whose reporting threads are gRPC's). Required.
  // Work it runs holds the engine: every item must have run and been destroyed before the
  // engine is (WorkQueue::Wait or Stop, then destroy the engine).
  std::function<void(std::function<void()>)> executor;
  // A task failure that is not handed back ends its job at once, with the task's own status,
  // instead of counting towards scheduler.max_task_failures: right in one process, where every
  // thread runs the same build on the same machine and a retry would fail the same way.
  bool task_failure_ends_job = false;
  // Milliseconds on any monotonic scale: lease deadlines and rates. Default: a steady clock.
  std::function<int64_t()> now_ms;
  // Running event lists (event_spill.h) held in memory, over every job, before a group's are
  // moved to a scratch file in `spill_dir`; "" keeps them all in memory (memory then grows
  // with the samples). Spilling changes no byte of any tile.
  std::string spill_dir;
  int64_t event_memory_budget_bytes = kDefaultEventMemoryBudget;
  FileSystem* fs = nullptr;  // for the scratch files; null: FileSystem::Default()
  // Called when verification quarantines a worker (scheduler.verify_fraction), with what it
  // found, after the engine has queued the recomputation of what the worker contributed. From
  // a reporting thread, no engine lock held.
  std::function<void(const std::string& worker_id, const std::string& why)> on_quarantine;
};

// A job to run.
struct EngineJob {
  std::string job_id;
  int priority = 0;
  int64_t sequence = 0;  // submission order, ascending
  std::shared_ptr<const BakePlan> plan;
  int samples_per_task = 0;     // light samples per task; 0: a whole stage in one task
  std::vector<int> done_tiles;  // tiles stored already (a resumed job): no work for them
  bool started = false;         // a task went out before (a resumed job): no Started() call
  std::shared_ptr<JobOutput> output;
};

struct EngineStats {
  SchedulerStats scheduler;
  int jobs_started = 0;  // with a task leased
  int jobs_waiting = 0;  // not yet
  // Over the last minute (or since the engine started, when younger).
  double tasks_per_second = 0;
  double events_per_second = 0;
};

class BakeEngine {
 public:
  explicit BakeEngine(EngineOptions options);
  ~BakeEngine();
  BakeEngine(const BakeEngine&) = delete;
  BakeEngine& operator=(const BakeEngine&) = delete;

  // The heap bytes the engine holds for a job of `tiles` tiles in `groups` tile groups, of
  // which `groups_with_work` have a tile a caster may reach, from AddJob to its end, besides
  // its plan, its open groups (bounded by SchedulerOptions::max_open_tiles and the event
  // memory budget) and the tiles no caster reaches until they are stored: a bit per tile and a
  // few words per group (verification's sums of each group's stored tiles; the scheduler's
  // entry of each group with work). What a coordinator counts against --max-planned-mib
  // (server/plan_budget.h); the coordinator's memory test checks it against the heap.
  static int64_t JobHeldBytes(int64_t tiles, int64_t groups, int64_t groups_with_work);

  // Starts scheduling the job. A job with every tile done goes straight to Finish (through the
  // executor). ALREADY_EXISTS when a job of that id is in progress; INVALID_ARGUMENT without a
  // plan or an output.
  absl::Status AddJob(EngineJob job);

  // The next task for `worker_id`. When none can go out now, waits up to `wait` for one
  // (results coming back open tiles and stages) and returns nullopt at the deadline or as soon
  // as no job is in progress.
  std::optional<TaskLease> Lease(const std::string& worker_id,
                                 absl::Duration wait = absl::ZeroDuration());

  // As Scheduler::Extend / FindLease.
  absl::StatusOr<int64_t> Extend(const std::string& worker_id, uint64_t lease_id);
  std::optional<TaskLease> FindLease(uint64_t lease_id) const;

  // A worker's events for its lease: one TileEvents per tile of the lease, in its order. Each
  // is merged into its tile's running lists at once, outside the engine's lock (under its
  // group's), and the group's lists move to the scratch file when the memory budget is spent.
  // A verification copy (TaskLease::verify, its task's second result) is only compared; a
  // worker it outvotes is quarantined and every group it fed, in every job not yet finishing,
  // is computed again: an assembled group is queued anew (its tiles withdrawn from the output),
  // an open one starts over when its stage completes.
  // REQUIRES: each fits its tile (the coordinator checks a remote worker's with
  // rpc/tile_events_codec.h). False when the result was dropped (late after expiry,
  // duplicate, job ended; a result with the wrong number of tiles counts as the task's
  // failure). When it completes a group's stage, the stage's judgement, assembly and storage
  // run through the executor before or after this returns.
  bool Report(const std::string& worker_id, uint64_t lease_id, std::vector<TileEvents> events);

  // The worker could not do the task (handed_back: it gave it up undone, e.g. stopping; it
  // counts against nobody). See EngineOptions::task_failure_ends_job.
  void ReportFailure(const std::string& worker_id, uint64_t lease_id, const absl::Status& status,
                     bool handed_back);

  // The worker plans the lease's job differently from this coordinator (Scheduler::
  // Incompatible): the task is requeued, counted against nobody, and the worker gets no more
  // of the job. True the first time for this (job, worker).
  bool ReportIncompatible(const std::string& worker_id, uint64_t lease_id);

  // The worker is leaving: no longer active (Scheduler::SignOff).
  void SignOff(const std::string& worker_id);

  // Verification has outvoted the worker (Scheduler::Quarantined).
  bool Quarantined(const std::string& worker_id) const;

  // Expires overdue leases and fails jobs no active worker can run (Scheduler::Tick).
  void Tick();

  // End the job as kCancelled or kFailed with `status` (a cancel by request; a failure found
  // outside the tasks, e.g. a local task runner that cannot start). False when the job is not
  // in progress.
  bool Cancel(const std::string& job_id, const absl::Status& status);
  bool Fail(const std::string& job_id, const absl::Status& status);

  // The job's plan, or null when it is not in progress.
  std::shared_ptr<const BakePlan> Plan(const std::string& job_id) const;
  // nullopt when the job is not in progress (never added, or ended).
  std::optional<JobProgress> Progress(const std::string& job_id) const;
  EngineStats Stats() const;

 private:
  struct Job;
  using JobPtr = std::shared_ptr<Job>;

  struct OpenGroup;
  using OpenGroupPtr = std::shared_ptr<OpenGroup>;
  // Merges a result's tiles into the group's running lists; spills them past the budget.
  absl::Status MergeResult(Job& job, OpenGroup& group, int sample_begin,
                           const std::vector<int>& tiles, std::vector<TileEvents> events);
  void CompleteStage(const JobPtr& job, int group_index, const OpenGroupPtr& group);
  // A completed stage's group reached through a result that brought no events (a vote, or a
  // task accepted unverified): schedules CompleteStage when no merge is running into it.
  // Returns the group when CompleteStage is the caller's to schedule (after the lock), null
  // when a merge still running into it will; INTERNAL when the group is not open (a broken
  // invariant: the caller fails the job rather than let it hang).
  absl::StatusOr<OpenGroupPtr> CompleteWithoutMerge(const JobPtr& job, const ResultOutcome& outcome)
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_);
  // What a job must give back to its output after a quarantine: (job, tiles).
  using Withdrawals = std::vector<std::pair<JobPtr, std::vector<int>>>;
  // Queues again, or marks for a restart, every group the workers fed in every job not yet
  // finishing; `summary` says what, for the log.
  Withdrawals Recompute(const std::vector<std::string>& workers, std::string* summary)
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_);
  // A tainted group whose stage completed starts over (Scheduler::RestartGroup); `withdrawn`
  // gets its tiles stored in earlier stages. False when the scheduler refused.
  bool RestartTainted(Job& job, int group_index, std::vector<int>* withdrawn)
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_);
  // Forgets what the group's tiles counted in the job's progress (they were stored) and what
  // its merged results counted; returns the tiles that were stored.
  std::vector<int> ForgetGroup(Job& job, int group_index, const std::vector<int>& tiles)
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_);
  void Withdraw(const Withdrawals& withdrawals);
  // Ends the job: the tile's spilled lists could not be read back.
  void FailReadingBack(const JobPtr& job, int tile_index, const absl::Status& status);
  // False when the job ended (the store failed, or it was ended meanwhile).
  bool StoreTile(const JobPtr& job, int tile_index, StageVerdict verdict);
  // JobOutput::CommitTiles; false when the job ended (it failed, which ends the job).
  bool CommitTiles(const JobPtr& job);
  // Stores the tiles no caster reaches (plan.tile_has_casters) all lit, without a task.
  void StoreUnreachedTiles(const JobPtr& job, const std::vector<int>& tiles);
  void FinishJob(const JobPtr& job);
  // Ends the job once; defers JobOutput::Ended until its output calls in flight return.
  void End(const JobPtr& job, JobEnd end, const absl::Status& status);
  bool EndById(const std::string& job_id, JobEnd end, const absl::Status& status);
  JobPtr FindJob(const std::string& job_id) const ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_);
  // Brackets a JobOutput call; false (no call) when the job has ended.
  bool BeginOutputCall(const JobPtr& job);
  void EndOutputCall(const JobPtr& job);
  int64_t TasksTotal(const Job& job) const ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_);
  void ForgetOldRates(int64_t now_ms) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_);

  const EngineOptions options_;
  const int64_t started_ms_;
  std::atomic<int64_t> event_memory_bytes_{0};  // running lists in memory, every open group

  mutable absl::Mutex mu_;
  absl::CondVar changed_;  // signalled when work may have become available or a job ended
  Scheduler scheduler_ ABSL_GUARDED_BY(mu_);
  std::map<std::string, JobPtr> jobs_ ABSL_GUARDED_BY(mu_);
  std::deque<std::pair<int64_t, int64_t>> recent_results_ ABSL_GUARDED_BY(mu_);  // (ms, events)
};

}  // namespace pdsm

#endif  // PDSM_CORE_PIPELINE_BAKE_ENGINE_H_
