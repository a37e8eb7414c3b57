// The scheduling state machine of every bake: which task a worker gets next, leases and their
// deadlines, failures, exclusions, cancellation. Pure logic with an explicit clock (`now_ms`),
// so tests drive it with a fake clock. Not thread-safe: core/pipeline/bake_engine.h owns one
// and calls it under its mutex, for the coordinator's remote workers and the local bake's
// threads alike.
//
// A job's work is its tile groups (core/bake/tile_groups.h) x sample batches: a task is one
// batch of samples for the tiles of one group still to do. Tasks are handed out group by
// group: a group opens only when no open group has a task waiting, and at most
// `max_open_tiles` tiles (over all jobs; one group at least) are in open groups, which is what
// bounds memory whatever the job size. Jobs run by priority (higher first), then in submission
// order. Adaptive jobs hand out a group's work in stages: the next stage's batches, for the
// tiles that need it, are queued only when the service calls AddStage().
//
// Verification by redundancy: tasks are deterministic, so two honest workers return the same
// bytes for one. A fraction of tasks (SchedulerOptions::verify_fraction), drawn at random as
// they are queued, is run by a second worker: the first result is merged at once, the second
// is only compared (by digest, core/pipeline/result_digest.h). When they differ a third worker
// decides; a worker outvoted two to one is quarantined (Quarantined()): it gets no more tasks of
// any job, its leases are taken back and its votes dropped, and the service recomputes what it
// contributed (RequeueGroup, RestartGroup). A worker is never asked to verify its own result
// and cannot tell a verification copy from a task.
#ifndef PDSM_CORE_PIPELINE_SCHEDULER_H_
#define PDSM_CORE_PIPELINE_SCHEDULER_H_

#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <random>
#include <set>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "absl/status/statusor.h"

namespace pdsm {

struct SchedulerOptions {
  int64_t lease_ms = 30'000;            // a lease lasts this long unless extended
  int max_task_failures = 3;            // distinct workers a task may fail on; then the job fails
  int max_worker_failures_per_job = 3;  // failures after which a worker gets no more of a job
  int max_open_tiles = 64;              // tiles of open groups, over all jobs (>= one group)
  int64_t worker_active_ms = 30'000;    // a worker is active if seen this recently
  uint64_t lease_id_base = 1;           // first lease id; a restarted coordinator picks a new
                                        // base so results for its predecessor's leases drop
  // Fraction of tasks run by two distinct workers and compared (see above), in [0, 1]; 0 turns
  // verification off (the local bake: its threads are one process). A verified task costs a
  // second run, so the farm does about (1 + verify_fraction) times the work.
  double verify_fraction = 0;
  // Seeds the draw of verified tasks; 0: std::random_device, so that no worker can predict
  // which of its tasks are checked. Tests fix it.
  uint64_t verify_seed = 0;
};

// A group's tiles still to do (a resumed job lists only its unfinished ones). Empty: every
// tile of the group there is work for, listed by JobSpec::tiles_of when the group opens, so
// that the groups a job has not opened yet hold no per-tile list.
struct GroupWork {
  int group_index = 0;
  std::vector<int> tiles;
};

struct JobSpec {
  std::string job_id;
  int priority = 0;
  int64_t sequence = 0;           // submission order, ascending
  std::vector<GroupWork> groups;  // in the order they open
  int samples = 1;                // light samples of the bake
  int samples_per_task = 1;       // batch size; the last batch of a range may be smaller
  // Adaptive sampling (core/bake/adaptive_sampling.h): > 0 makes a group's work come in
  // stages of these first samples; after each stage completes the service assembles the tiles
  // that are done and calls AddStage() for the others. 0: one stage holding all `samples`.
  int adaptive_min_samples = 0;
  // The tiles of a group whose GroupWork lists none (non-empty, any order). Required when
  // one does; called under the scheduler's caller's lock, so it must be quick and lock-free.
  std::function<std::vector<int>(int group_index)> tiles_of;
};

struct TaskLease {
  uint64_t lease_id = 0;
  std::string job_id;
  int group_index = 0;
  std::vector<int> tiles;  // the group's tiles of this stage, ascending
  int sample_begin = 0, sample_end = 0;
  int64_t deadline_ms = 0;
  // The task is one verification draws (its result's digest is needed by Complete). The
  // service never tells the worker.
  bool verify = false;
};

struct JobFailure {
  std::string job_id;
  std::string reason;
};

// What happened to a reported result.
struct ResultOutcome {
  // kAccepted: the result counts (merged, or a vote on a verified task); kStageComplete: and
  // with it every batch of the group's stage is done.
  enum Kind { kDropped, kAccepted, kStageComplete } kind = kDropped;
  std::string job_id;  // set unless dropped
  int group_index = 0;
  std::vector<int> tiles;
  int sample_begin = 0, sample_end = 0;
  // The service merges this result's events: true for an unverified task and for a verified
  // task's first result; a later vote is only compared.
  bool merge = false;
  // Workers this result outvoted, now quarantined (the service recomputes what they merged).
  std::vector<std::string> quarantined;
  // Set (with kind kDropped) when the votes on this task cannot agree: the job is removed.
  std::optional<JobFailure> failure;
};

struct SchedulerStats {
  int tasks_pending = 0;
  int tasks_leased = 0;
  int tiles_open = 0;  // tiles of open groups
  int workers_active = 0;
  int64_t leases_expired = 0;
  int64_t results_dropped = 0;
  int64_t results_accepted = 0;
  int workers_incompatible = 0;         // (job, worker) pairs of jobs in progress (Incompatible())
  int workers_quarantined = 0;          // outvoted by verification, since the scheduler started
  int tasks_awaiting_verification = 0;  // first result in, second not yet
  // Since the scheduler started (counters, for metrics):
  int64_t leases_issued = 0;
  int64_t tasks_failed = 0;  // reported failures (Fail, not handed back)
  std::map<absl::StatusCode, int64_t> tasks_failed_by_code;  // the same, by Fail's code
  int64_t tasks_handed_back = 0;                             // Fail with handed_back
  int64_t tasks_incompatible = 0;       // current leases reported by Incompatible()
  int64_t tasks_verified = 0;           // verified tasks whose two results agreed at once
  int64_t verification_mismatches = 0;  // verified tasks decided against a disagreeing worker
  int64_t tasks_unverified = 0;         // drawn for verification, accepted on one result: no other
                                        // able worker was active
};

class Scheduler {
 public:
  explicit Scheduler(SchedulerOptions options);

  // REQUIRES: job_id not already present. A job with no groups is complete at once.
  void AddJob(const JobSpec& job);

  // The next task for `worker_id`, or nullopt when none may be issued now. Records the worker
  // as seen. Never gives a worker a task of a job it is excluded from, nor a task it failed.
  // Nor a task of a job it is incompatible with (Incompatible()).
  std::optional<TaskLease> Lease(const std::string& worker_id, int64_t now_ms);

  // New deadline. FAILED_PRECONDITION when the lease is not current or not this worker's.
  absl::StatusOr<int64_t> Extend(const std::string& worker_id, uint64_t lease_id, int64_t now_ms);

  // Accepts the result of a current lease held by `worker_id`; anything else is dropped
  // (late after expiry, duplicate, cancelled job, unknown lease). kStageComplete: every batch
  // of that group's stage is now accepted; the service then calls AddStage() for the tiles
  // that need more and GroupAssembled() when none does. A lease expires when Tick()
  // finds its deadline passed; until then it is current. Extend, Complete and Fail also record
  // the worker as seen (a worker busy on a long task is active).
  // `digest`: of the result (core/pipeline/result_digest.h), required when the lease's
  // `verify` is set, else ignored. A verified task is done when two distinct workers' digests
  // agree; workers whose digest differs from those two are quarantined. Before that its task
  // goes back to the queue for a worker that has not voted on it; with no such worker active,
  // a lone first result is accepted unverified (counted in tasks_unverified). When more than
  // max_task_failures + 1 workers have voted and no two agree, the job fails.
  ResultOutcome Complete(const std::string& worker_id, uint64_t lease_id, int64_t now_ms,
                         std::string_view digest = {});

  // The worker could not do the task. Unless `handed_back`, it counts against the worker and
  // the task; the task goes back to the queue. Returns the job's failure when the task has now
  // failed on max_task_failures distinct workers (the job is then removed).
  // `code`: the failure's status code, counted in SchedulerStats::tasks_failed_by_code.
  std::optional<JobFailure> Fail(const std::string& worker_id, uint64_t lease_id,
                                 const std::string& reason, bool handed_back, int64_t now_ms,
                                 absl::StatusCode code = absl::StatusCode::kUnknown);

  // The worker's build plans the lease's job differently (a plan-fingerprint mismatch: a
  // rolling upgrade, another libm): not a failure of anyone. The task goes back to the queue
  // and the worker gets no more of that job's tasks; the job waits for a compatible worker
  // however long that takes (it never fails for it: Tick() counts incompatible workers as
  // able). True when this marked the pair for the first time (the service logs it once);
  // false for a lease that is not current or not this worker's.
  bool Incompatible(const std::string& worker_id, uint64_t lease_id, int64_t now_ms);

  // The worker is leaving (it handed back its tasks first): it stops counting as active at
  // once instead of worker_active_ms after its last call. Its current leases, if any, stay
  // until they expire.
  void SignOff(const std::string& worker_id);

  // Re-queues tasks whose lease has expired and fails jobs that can no longer progress: a task
  // failed on too many workers, or every active worker excluded. An expiry says the holder
  // went quiet (dead, stopped, cut off), not that it cannot do the task: it counts towards the
  // task's max_task_failures once per distinct worker (a task that kills every process it
  // reaches, each a new worker id, still fails its job), but never towards the worker's
  // exclusion, and the worker may take the task again, so that a farm of one worker whose
  // machine pauses (a suspended VM, a network cut) finishes its jobs. Call periodically.
  std::vector<JobFailure> Tick(int64_t now_ms);

  // Verified tasks waiting for a second result that no active worker can give (every able one
  // voted already, or left): accepted on their one result, as Complete would have (kAccepted or
  // kStageComplete, merge false). Call periodically, after Tick.
  std::vector<ResultOutcome> AcceptUnverifiable(int64_t now_ms);

  // True once verification has outvoted the worker (for the scheduler's lifetime).
  bool Quarantined(const std::string& worker_id) const;

  // Verification found a worker wrong: what it merged must be computed again.
  // An assembled group (GroupAssembled called) is queued again as at AddJob, with the tiles it
  // had then, which are returned; nullopt, changing nothing, when the group is open (restart it
  // when its stage completes), already queued again, or unknown.
  std::optional<std::vector<int>> RequeueGroup(const std::string& job_id, int group_index);
  // An open group whose stage just completed (kStageComplete) starts over at its first stage
  // with the tiles it had at AddJob, which are returned (the service stored some of them in
  // earlier stages); nullopt, changing nothing, when it is not open or has work outstanding.
  std::optional<std::vector<int>> RestartGroup(const std::string& job_id, int group_index);

  // Adaptive jobs: queues the next stage of a group whose stage just completed
  // (kStageComplete) for `tiles`, a non-empty subset of its stage's tiles (the others are
  // done). Returns false, changing nothing, for an unknown job or group, a group with work
  // outstanding, tiles not of its stage, a fixed-count job, or a group past its last stage.
  bool AddStage(const std::string& job_id, int group_index, const std::vector<int>& tiles);

  // Frees the group's slot once the service has stored every tile of it.
  // REQUIRES: Complete() returned kStageComplete for its last stage.
  void GroupAssembled(const std::string& job_id, int group_index);

  // True when every group of the job is assembled (the job then leaves the scheduler after
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
  // A sample batch of an open group.
  struct Task {
    int sample_begin = 0, sample_end = 0;
    bool done = false;
    std::optional<uint64_t> lease_id;  // set while leased
    // (worker, reason) of each failure; the workers are distinct since a task never goes back
    // to a worker it failed on.
    std::vector<std::pair<std::string, std::string>> failures;
    // Workers whose lease of it expired (Tick): counted with `failures` (once per worker, and
    // not again when the worker also failed it), but not keeping it from them.
    std::set<std::string> expired_on;
    bool verify = false;  // drawn for verification
    bool merged = false;  // a result of it has been merged (the first vote)
    // (worker, digest) of each result of a verified task, distinct workers, until decided.
    std::vector<std::pair<std::string, std::string>> votes;
  };
  // A group from its opening until GroupAssembled(). Unopened groups are only entries of
  // Job::group_order, so a job's memory follows its open groups, not its size.
  struct Group {
    int position = 0;         // in Job::group_order
    int stage = 0;            // adaptive jobs: the stage whose tasks are the last of `tasks`
    std::vector<int> tiles;   // the current stage's
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
  // (position of the group in Job::group_order, batch): sorted, it is the order tasks go out.
  using TaskRef = std::pair<int, int>;
  struct Job {
    JobKey key;
    int samples = 1;
    int samples_per_task = 1;
    int adaptive_min_samples = 0;        // 0: fixed-count job
    std::vector<GroupWork> group_order;  // groups in the order they open
    size_t next_group = 0;               // next group of group_order to open
    std::vector<int> next_group_tiles;   // its tiles, once listed (WorkTiles), until it opens
    std::function<std::vector<int>(int)> tiles_of;  // JobSpec::tiles_of
    std::map<int, Group> groups;                    // open groups by group index
    std::set<TaskRef> pending;                      // tasks of open groups waiting for a worker
    std::set<TaskRef> awaiting;                     // verified tasks with votes, not yet decided
    std::set<uint64_t> leases;                      // current leases
    int64_t tasks_left = 0;                         // not yet accepted, open or not
    int groups_left = 0;                            // not yet assembled
    std::map<std::string, int> worker_failures;
    std::set<std::string> incompatible_workers;  // plan their own way: get none of its tasks
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
  // Whether the worker may take the task: it has neither failed nor voted on it.
  static bool MayTake(const Task& task, const std::string& worker_id);
  // Marks the task accepted and fills the outcome's kind.
  void MarkDone(Job& job, TaskRef task, ResultOutcome* outcome);
  // A verified task's votes so far: decides it, quarantines the outvoted, requeues it for
  // another vote or fails the job (outcome->failure).
  void Decide(Job& job, TaskRef task, int64_t now_ms, ResultOutcome* outcome);
  // Some active worker could give the task another vote.
  bool CanVerify(const Job& job, const Task& task, int64_t now_ms) const;
  void Quarantine(const std::string& worker_id);
  ResultOutcome OutcomeOf(const Job& job, TaskRef task) const;
  bool OpenGroup(Job& job);
  // The group's tiles, ascending, without repeats: its own list, or JobSpec::tiles_of's.
  static std::vector<int> WorkTiles(const Job& job, const GroupWork& work);
  // The sample ranges of a group's stage, cut into batches of samples_per_task.
  static std::vector<std::pair<int, int>> StageBatches(const Job& job, int stage);
  void AddTasks(Job& job, Group& group, int stage);
  TaskLease Issue(Job& job, TaskRef task, const std::string& worker_id, int64_t now_ms);
  Group& GroupOf(Job& job, TaskRef task);
  const Group& GroupOf(const Job& job, TaskRef task) const;
  TaskLease LeaseOf(uint64_t lease_id, const LeaseInfo& info) const;
  LeaseMap::iterator FindCurrent(const std::string& worker_id, uint64_t lease_id);
  LeaseInfo TakeLease(LeaseMap::iterator it);
  void Requeue(Job& job, TaskRef task);
  // Takes the lease back and requeues its task, counting `reason` against the worker and
  // the task unless `handed_back`, or as an expiry when `expired`.
  std::optional<JobFailure> FailTask(LeaseMap::iterator it, const std::string& reason,
                                     bool handed_back, bool expired = false);
  std::optional<JobFailure> CountFailure(Job& job, TaskRef task, const std::string& worker_id,
                                         const std::string& reason);
  // The worker's lease of the task expired (Tick).
  std::optional<JobFailure> CountExpiry(Job& job, TaskRef task, const std::string& worker_id,
                                        const std::string& reason);
  // The job's failure once the task has failed (or expired) on max_task_failures workers.
  std::optional<JobFailure> TaskFailedTooOften(const Job& job, TaskRef task) const;
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
  std::set<JobKey> ready_;  // jobs with pending tasks of open groups
  LeaseMap leases_;
  std::set<std::pair<int64_t, uint64_t>> deadlines_;  // (deadline, lease id) of current leases
  std::map<std::string, int64_t> worker_seen_ms_;
  std::set<std::pair<int64_t, std::string>> workers_by_seen_;  // (last seen, worker)
  std::set<std::string> quarantined_;
  std::mt19937_64 verify_draw_;
  int tiles_open_ = 0;
  int64_t leases_expired_ = 0;
  int64_t results_dropped_ = 0;
  int64_t results_accepted_ = 0;
  int64_t leases_issued_ = 0;
  int64_t tasks_failed_ = 0;
  std::map<absl::StatusCode, int64_t> tasks_failed_by_code_;
  int64_t tasks_handed_back_ = 0;
  int64_t tasks_incompatible_ = 0;
  int64_t tasks_verified_ = 0;
  int64_t verification_mismatches_ = 0;
  int64_t tasks_unverified_ = 0;
};

}  // namespace pdsm

#endif  // PDSM_CORE_PIPELINE_SCHEDULER_H_
