#include "core/pipeline/scheduler.h"

#include <algorithm>
#include <utility>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "core/bake/adaptive_sampling.h"

namespace pdsm {

// A lease is current from Issue() until it completes, fails or Tick() finds its deadline
// passed; Extend() and Complete() in between are honoured even past the deadline, since no
// other worker has been given the task yet and the work is not lost.

bool Scheduler::JobKey::operator<(const JobKey& o) const {
  if (priority != o.priority) return priority > o.priority;
  if (sequence != o.sequence) return sequence < o.sequence;
  return job_id < o.job_id;
}

namespace {

uint64_t VerifySeed(uint64_t seed) {
  if (seed != 0) return seed;
  std::random_device device;
  return (uint64_t{device()} << 32) ^ device();
}

}  // namespace

Scheduler::Scheduler(SchedulerOptions options)
    : options_(options),
      next_lease_id_(options.lease_id_base),
      verify_draw_(VerifySeed(options.verify_seed)) {}

void Scheduler::AddJob(const JobSpec& spec) {
  Job& job = jobs_[spec.job_id];
  job.key = {spec.priority, spec.sequence, spec.job_id};
  // Nonsensical sizes become one sample per batch rather than tiles that never complete.
  job.samples = std::max(1, spec.samples);
  job.samples_per_task = std::max(1, spec.samples_per_task);
  job.adaptive_min_samples = std::clamp(spec.adaptive_min_samples, 0, job.samples);
  job.tiles_of = spec.tiles_of;
  job.group_order.reserve(spec.groups.size());  // a coordinator counts it (JobHeldBytes)
  std::set<int> seen;
  for (const GroupWork& group : spec.groups) {
    // A repeat is the same group; a group without its own list needs tiles_of.
    if ((!group.tiles.empty() || job.tiles_of) && seen.insert(group.group_index).second) {
      job.group_order.push_back(group);
    }
  }
  job.groups_left = static_cast<int>(job.group_order.size());
  // Adaptive jobs: the tasks known so far (every group's pilot); later stages add theirs.
  job.tasks_left = int64_t{job.groups_left} * static_cast<int64_t>(StageBatches(job, 0).size());
  order_.insert(job.key);
}

std::optional<TaskLease> Scheduler::Lease(const std::string& worker_id, int64_t now_ms) {
  if (quarantined_.contains(worker_id)) return std::nullopt;
  Touch(worker_id, now_ms);
  // With every tile slot taken only pending tasks of open groups can go out, so the walk can
  // skip the jobs that have none.
  const std::set<JobKey>& walk = tiles_open_ < options_.max_open_tiles ? order_ : ready_;
  for (const JobKey& key : walk) {
    Job& job = jobs_.at(key.job_id);
    if (Excluded(job, worker_id) || job.incompatible_workers.contains(worker_id)) continue;
    if (std::optional<TaskLease> lease = TryLease(job, worker_id, now_ms)) return lease;
  }
  return std::nullopt;
}

std::optional<TaskLease> Scheduler::TryLease(Job& job, const std::string& worker_id,
                                             int64_t now_ms) {
  // A worker skips only the tasks it failed on, fewer than max_worker_failures_per_job
  // since it is not excluded, and those it voted on.
  for (const TaskRef& task : job.pending) {
    if (MayTake(GroupOf(job, task).tasks[task.second], worker_id)) {
      return Issue(job, task, worker_id, now_ms);
    }
  }
  // A freshly opened group's first batch has failed on nobody.
  if (OpenGroup(job)) {
    return Issue(job, {static_cast<int>(job.next_group) - 1, 0}, worker_id, now_ms);
  }
  return std::nullopt;
}

bool Scheduler::MayTake(const Task& task, const std::string& worker_id) {
  const auto is_worker = [&](const auto& entry) { return entry.first == worker_id; };
  return std::none_of(task.failures.begin(), task.failures.end(), is_worker) &&
         std::none_of(task.votes.begin(), task.votes.end(), is_worker);
}

std::vector<int> Scheduler::WorkTiles(const Job& job, const GroupWork& work) {
  std::vector<int> tiles = work.tiles.empty() ? job.tiles_of(work.group_index) : work.tiles;
  std::sort(tiles.begin(), tiles.end());
  tiles.erase(std::unique(tiles.begin(), tiles.end()), tiles.end());
  return tiles;
}

bool Scheduler::OpenGroup(Job& job) {
  if (job.next_group >= job.group_order.size()) return false;
  const GroupWork& work = job.group_order[job.next_group];
  // Listed once while it waits for room (Lease asks again and again).
  if (job.next_group_tiles.empty()) job.next_group_tiles = WorkTiles(job, work);
  // The tile budget holds unless no group is open at all: a group larger than the budget
  // still gets its turn.
  const int tiles = static_cast<int>(job.next_group_tiles.size());
  if (tiles_open_ > 0 && tiles_open_ + tiles > options_.max_open_tiles) return false;
  const int position = static_cast<int>(job.next_group++);
  Group& group = job.groups[work.group_index];
  group.position = position;
  group.tiles = std::move(job.next_group_tiles);
  job.next_group_tiles.clear();
  tiles_open_ += static_cast<int>(group.tiles.size());
  AddTasks(job, group, 0);
  return true;
}

std::vector<std::pair<int, int>> Scheduler::StageBatches(const Job& job, int stage) {
  std::vector<SampleRange> ranges;
  if (job.adaptive_min_samples > 0) {
    ranges = AdaptiveStageRanges(stage, job.adaptive_min_samples, job.samples);
  } else if (stage == 0) {
    ranges.push_back({0, job.samples});
  }
  std::vector<std::pair<int, int>> batches;
  for (const SampleRange& r : ranges) {
    for (int64_t b = r.begin; b < r.end; b += job.samples_per_task) {
      batches.emplace_back(static_cast<int>(b),
                           static_cast<int>(std::min<int64_t>(r.end, b + job.samples_per_task)));
    }
  }
  return batches;
}

void Scheduler::AddTasks(Job& job, Group& group, int stage) {
  group.stage = stage;
  group.tasks_left = 0;
  for (const auto& [begin, end] : StageBatches(job, stage)) {
    job.pending.insert({group.position, static_cast<int>(group.tasks.size())});
    Task task;
    task.sample_begin = begin;
    task.sample_end = end;
    // Drawn for every task, verified or not, so that the draw does not depend on the fraction.
    task.verify =
        std::uniform_real_distribution<double>(0.0, 1.0)(verify_draw_) < options_.verify_fraction;
    group.tasks.push_back(std::move(task));
    ++group.tasks_left;
  }
  UpdateReady(job);
}

bool Scheduler::AddStage(const std::string& job_id, int group_index,
                         const std::vector<int>& tiles) {
  const auto job_it = jobs_.find(job_id);
  if (job_it == jobs_.end() || job_it->second.adaptive_min_samples == 0) return false;
  Job& job = job_it->second;
  const auto group_it = job.groups.find(group_index);
  if (group_it == job.groups.end() || group_it->second.tasks_left > 0 || tiles.empty()) {
    return false;
  }
  Group& group = group_it->second;
  std::vector<int> next = tiles;
  std::sort(next.begin(), next.end());
  next.erase(std::unique(next.begin(), next.end()), next.end());
  if (!std::includes(group.tiles.begin(), group.tiles.end(), next.begin(), next.end())) {
    return false;
  }
  const size_t added = StageBatches(job, group.stage + 1).size();
  if (added == 0) return false;
  tiles_open_ -= static_cast<int>(group.tiles.size() - next.size());  // the done ones leave
  group.tiles = std::move(next);
  AddTasks(job, group, group.stage + 1);
  job.tasks_left += static_cast<int64_t>(added);
  return true;
}

TaskLease Scheduler::Issue(Job& job, TaskRef task, const std::string& worker_id, int64_t now_ms) {
  const uint64_t lease_id = next_lease_id_++;
  ++leases_issued_;
  const int64_t deadline_ms = now_ms + options_.lease_ms;
  job.pending.erase(task);
  UpdateReady(job);
  GroupOf(job, task).tasks[task.second].lease_id = lease_id;
  job.leases.insert(lease_id);
  const LeaseInfo& info = leases_[lease_id] = {job.key.job_id, task, worker_id, deadline_ms};
  deadlines_.insert({deadline_ms, lease_id});
  return LeaseOf(lease_id, info);
}

Scheduler::Group& Scheduler::GroupOf(Job& job, TaskRef task) {
  return job.groups.at(job.group_order[task.first].group_index);
}

const Scheduler::Group& Scheduler::GroupOf(const Job& job, TaskRef task) const {
  return job.groups.at(job.group_order[task.first].group_index);
}

TaskLease Scheduler::LeaseOf(uint64_t lease_id, const LeaseInfo& info) const {
  const Job& job = jobs_.at(info.job_id);
  const Group& group = GroupOf(job, info.task);
  const Task& task = group.tasks[info.task.second];
  TaskLease lease;
  lease.lease_id = lease_id;
  lease.job_id = info.job_id;
  lease.group_index = job.group_order[info.task.first].group_index;
  lease.tiles = group.tiles;
  lease.sample_begin = task.sample_begin;
  lease.sample_end = task.sample_end;
  lease.deadline_ms = info.deadline_ms;
  lease.verify = task.verify;
  return lease;
}

absl::StatusOr<int64_t> Scheduler::Extend(const std::string& worker_id, uint64_t lease_id,
                                          int64_t now_ms) {
  Touch(worker_id, now_ms);
  const LeaseMap::iterator it = FindCurrent(worker_id, lease_id);
  if (it == leases_.end()) {
    return absl::FailedPreconditionError(
        absl::StrCat("lease ", lease_id, " is not a current lease of worker ", worker_id));
  }
  LeaseInfo& lease = it->second;
  deadlines_.erase({lease.deadline_ms, lease_id});
  lease.deadline_ms = now_ms + options_.lease_ms;
  deadlines_.insert({lease.deadline_ms, lease_id});
  return lease.deadline_ms;
}

ResultOutcome Scheduler::Complete(const std::string& worker_id, uint64_t lease_id, int64_t now_ms,
                                  std::string_view digest) {
  Touch(worker_id, now_ms);
  const LeaseMap::iterator it = FindCurrent(worker_id, lease_id);
  if (it == leases_.end()) {
    ++results_dropped_;
    return {};
  }
  const LeaseInfo lease = TakeLease(it);
  Job& job = jobs_.at(lease.job_id);
  Task& task = GroupOf(job, lease.task).tasks[lease.task.second];
  ++results_accepted_;
  ResultOutcome outcome = OutcomeOf(job, lease.task);
  outcome.kind = ResultOutcome::kAccepted;
  outcome.merge = !task.merged;
  task.merged = true;
  if (!task.verify) {
    MarkDone(job, lease.task, &outcome);
    return outcome;
  }
  task.votes.emplace_back(worker_id, std::string(digest));
  Decide(job, lease.task, now_ms, &outcome);
  return outcome;
}

ResultOutcome Scheduler::OutcomeOf(const Job& job, TaskRef task) const {
  const Group& group = GroupOf(job, task);
  ResultOutcome outcome;
  outcome.job_id = job.key.job_id;
  outcome.group_index = job.group_order[task.first].group_index;
  outcome.tiles = group.tiles;
  outcome.sample_begin = group.tasks[task.second].sample_begin;
  outcome.sample_end = group.tasks[task.second].sample_end;
  return outcome;
}

void Scheduler::MarkDone(Job& job, TaskRef task, ResultOutcome* outcome) {
  Group& group = GroupOf(job, task);
  Task& t = group.tasks[task.second];
  t.done = true;
  t.votes.clear();
  job.awaiting.erase(task);
  --group.tasks_left;
  --job.tasks_left;
  outcome->kind = group.tasks_left == 0 ? ResultOutcome::kStageComplete : ResultOutcome::kAccepted;
}

void Scheduler::Decide(Job& job, TaskRef task, int64_t now_ms, ResultOutcome* outcome) {
  Task& t = GroupOf(job, task).tasks[task.second];
  std::map<std::string, int> tally;
  for (const auto& [worker, digest] : t.votes) ++tally[digest];
  const auto agreed = std::max_element(
      tally.begin(), tally.end(), [](const auto& a, const auto& b) { return a.second < b.second; });
  if (agreed->second >= 2) {
    const std::string digest = agreed->first;
    std::vector<std::string> outvoted, agreeing;
    for (const auto& [worker, d] : t.votes) (d == digest ? agreeing : outvoted).push_back(worker);
    ++(outvoted.empty() ? tasks_verified_ : verification_mismatches_);
    MarkDone(job, task, outcome);
    for (const std::string& worker : outvoted) {
      if (quarantined_.contains(worker)) continue;
      Quarantine(worker);
      outcome->quarantined.push_back(worker);
    }
    return;
  }
  if (t.votes.size() == 1 && !CanVerify(job, t, now_ms)) {
    ++tasks_unverified_;
    MarkDone(job, task, outcome);
    return;
  }
  if (static_cast<int>(t.votes.size()) > options_.max_task_failures + 1) {
    std::string why =
        absl::StrCat("tile group ", job.group_order[task.first].group_index, " samples [",
                     t.sample_begin, ", ", t.sample_end, "): ", t.votes.size(),
                     " workers returned ", tally.size(), " different results and no two agree:");
    for (const auto& [worker, digest] : t.votes) {
      absl::StrAppend(&why, " ", worker, " (", digest.substr(0, 12), ")");
    }
    outcome->kind = ResultOutcome::kDropped;
    outcome->failure = JobFailure{job.key.job_id, std::move(why)};
    RemoveJob(job.key.job_id);
    return;
  }
  job.awaiting.insert(task);
  Requeue(job, task);
}

bool Scheduler::CanVerify(const Job& job, const Task& task, int64_t now_ms) const {
  for (auto it = workers_by_seen_.rbegin(); it != workers_by_seen_.rend(); ++it) {
    const auto& [seen_ms, worker_id] = *it;
    if (now_ms - seen_ms > options_.worker_active_ms) break;  // the rest are older
    if (job.incompatible_workers.contains(worker_id) || Excluded(job, worker_id)) continue;
    if (MayTake(task, worker_id)) return true;
  }
  return false;
}

std::vector<ResultOutcome> Scheduler::AcceptUnverifiable(int64_t now_ms) {
  std::vector<ResultOutcome> accepted;
  for (auto& [job_id, job] : jobs_) {
    // Copied: MarkDone erases from it.
    const std::vector<TaskRef> awaiting(job.awaiting.begin(), job.awaiting.end());
    for (const TaskRef& ref : awaiting) {
      const Task& task = GroupOf(job, ref).tasks[ref.second];
      // Leased: a vote is on its way. Two votes that differ need a third, however long.
      if (task.lease_id || task.votes.size() != 1 || CanVerify(job, task, now_ms)) continue;
      ResultOutcome outcome = OutcomeOf(job, ref);
      job.pending.erase(ref);
      UpdateReady(job);
      ++tasks_unverified_;
      MarkDone(job, ref, &outcome);
      accepted.push_back(std::move(outcome));
    }
  }
  return accepted;
}

bool Scheduler::Quarantined(const std::string& worker_id) const {
  return quarantined_.contains(worker_id);
}

void Scheduler::Quarantine(const std::string& worker_id) {
  quarantined_.insert(worker_id);
  // Its leases are taken back (results it sends now are dropped) and it stops counting as an
  // active worker.
  for (auto it = leases_.begin(); it != leases_.end();) {
    const auto next = std::next(it);
    if (it->second.worker_id == worker_id) {
      const LeaseInfo lease = TakeLease(it);
      Requeue(jobs_.at(lease.job_id), lease.task);
    }
    it = next;
  }
  SignOff(worker_id);
  // Its votes no longer count: a task it voted on waits for an honest second opinion.
  for (auto& [job_id, job] : jobs_) {
    for (const TaskRef& ref : job.awaiting) {
      std::vector<std::pair<std::string, std::string>>& votes =
          GroupOf(job, ref).tasks[ref.second].votes;
      std::erase_if(votes, [&](const auto& vote) { return vote.first == worker_id; });
    }
  }
}

std::optional<std::vector<int>> Scheduler::RequeueGroup(const std::string& job_id,
                                                        int group_index) {
  const auto job_it = jobs_.find(job_id);
  if (job_it == jobs_.end()) return std::nullopt;
  Job& job = job_it->second;
  if (job.groups.contains(group_index)) return std::nullopt;  // open
  // Its latest entry: one not opened yet means it is queued again already.
  std::optional<size_t> latest;
  for (size_t i = 0; i < job.group_order.size(); ++i) {
    if (job.group_order[i].group_index == group_index) latest = i;
  }
  if (!latest || *latest >= job.next_group) return std::nullopt;
  const GroupWork again = job.group_order[*latest];
  job.group_order.push_back(again);
  ++job.groups_left;
  job.tasks_left += static_cast<int64_t>(StageBatches(job, 0).size());
  return WorkTiles(job, again);
}

std::optional<std::vector<int>> Scheduler::RestartGroup(const std::string& job_id,
                                                        int group_index) {
  const auto job_it = jobs_.find(job_id);
  if (job_it == jobs_.end()) return std::nullopt;
  Job& job = job_it->second;
  const auto group_it = job.groups.find(group_index);
  if (group_it == job.groups.end() || group_it->second.tasks_left > 0) return std::nullopt;
  Group& group = group_it->second;
  std::vector<int> tiles = WorkTiles(job, job.group_order[group.position]);
  tiles_open_ += static_cast<int>(tiles.size()) - static_cast<int>(group.tiles.size());
  group.tiles = tiles;
  group.tasks.clear();  // all done: no lease, pending entry or vote refers to them
  AddTasks(job, group, 0);
  job.tasks_left += group.tasks_left;
  return tiles;
}

std::optional<JobFailure> Scheduler::Fail(const std::string& worker_id, uint64_t lease_id,
                                          const std::string& reason, bool handed_back,
                                          int64_t now_ms, absl::StatusCode code) {
  Touch(worker_id, now_ms);
  const LeaseMap::iterator it = FindCurrent(worker_id, lease_id);
  if (it == leases_.end()) return std::nullopt;  // stale: the task is already elsewhere
  ++(handed_back ? tasks_handed_back_ : tasks_failed_);
  if (!handed_back) ++tasks_failed_by_code_[code];
  return FailTask(it, reason, handed_back);
}

bool Scheduler::Incompatible(const std::string& worker_id, uint64_t lease_id, int64_t now_ms) {
  Touch(worker_id, now_ms);
  const LeaseMap::iterator it = FindCurrent(worker_id, lease_id);
  if (it == leases_.end()) return false;
  ++tasks_incompatible_;
  const LeaseInfo lease = TakeLease(it);
  Job& job = jobs_.at(lease.job_id);
  Requeue(job, lease.task);
  return job.incompatible_workers.insert(worker_id).second;
}

void Scheduler::SignOff(const std::string& worker_id) {
  const auto it = worker_seen_ms_.find(worker_id);
  if (it == worker_seen_ms_.end()) return;
  workers_by_seen_.erase({it->second, worker_id});
  worker_seen_ms_.erase(it);
}

std::vector<JobFailure> Scheduler::Tick(int64_t now_ms) {
  std::vector<JobFailure> failures;
  // A failing job takes its other leases out of deadlines_, so always restart at the front.
  while (!deadlines_.empty() && deadlines_.begin()->first <= now_ms) {
    const LeaseMap::iterator it = leases_.find(deadlines_.begin()->second);
    ++leases_expired_;
    const std::string reason = absl::StrCat("lease expired on worker ", it->second.worker_id);
    if (std::optional<JobFailure> failure =
            FailTask(it, reason, /*handed_back=*/false, /*expired=*/true)) {
      failures.push_back(*std::move(failure));
    }
  }
  ForgetInactiveWorkers(now_ms);
  std::vector<JobFailure> stuck;
  for (const auto& [job_id, job] : jobs_) {
    if (std::optional<JobFailure> failure = CheckStuck(job)) {
      stuck.push_back(*std::move(failure));
    }
  }
  for (JobFailure& failure : stuck) {
    RemoveJob(failure.job_id);
    failures.push_back(std::move(failure));
  }
  return failures;
}

void Scheduler::GroupAssembled(const std::string& job_id, int group_index) {
  const auto job_it = jobs_.find(job_id);
  if (job_it == jobs_.end()) return;
  Job& job = job_it->second;
  const auto group_it = job.groups.find(group_index);
  if (group_it == job.groups.end() || group_it->second.tasks_left > 0) return;
  tiles_open_ -= static_cast<int>(group_it->second.tiles.size());
  job.groups.erase(group_it);
  --job.groups_left;
}

bool Scheduler::JobComplete(const std::string& job_id) const {
  const auto it = jobs_.find(job_id);
  return it != jobs_.end() && it->second.groups_left == 0;
}

void Scheduler::RemoveJob(const std::string& job_id) {
  const auto it = jobs_.find(job_id);
  if (it == jobs_.end()) return;
  Job& job = it->second;
  for (uint64_t lease_id : job.leases) {
    const LeaseMap::iterator lease = leases_.find(lease_id);
    deadlines_.erase({lease->second.deadline_ms, lease_id});
    leases_.erase(lease);
  }
  for (const auto& [index, group] : job.groups) tiles_open_ -= static_cast<int>(group.tiles.size());
  order_.erase(job.key);
  ready_.erase(job.key);
  jobs_.erase(it);
}

std::optional<TaskLease> Scheduler::FindLease(uint64_t lease_id) const {
  const auto it = leases_.find(lease_id);
  if (it == leases_.end()) return std::nullopt;
  return LeaseOf(lease_id, it->second);
}

bool Scheduler::HasJob(const std::string& job_id) const { return jobs_.contains(job_id); }

std::optional<int64_t> Scheduler::TasksLeft(const std::string& job_id) const {
  const auto it = jobs_.find(job_id);
  if (it == jobs_.end()) return std::nullopt;
  return it->second.tasks_left;
}

SchedulerStats Scheduler::Stats(int64_t now_ms) const {
  SchedulerStats stats;
  for (const auto& [job_id, job] : jobs_) {
    stats.tasks_pending += static_cast<int>(job.tasks_left - job.leases.size());
    stats.workers_incompatible += static_cast<int>(job.incompatible_workers.size());
    stats.tasks_awaiting_verification += static_cast<int>(job.awaiting.size());
  }
  stats.workers_quarantined = static_cast<int>(quarantined_.size());
  stats.tasks_verified = tasks_verified_;
  stats.verification_mismatches = verification_mismatches_;
  stats.tasks_unverified = tasks_unverified_;
  stats.tasks_leased = static_cast<int>(leases_.size());
  stats.tiles_open = tiles_open_;
  // Workers Tick() has not yet forgotten sit at the front.
  int inactive = 0;
  for (const auto& [seen_ms, worker_id] : workers_by_seen_) {
    if (now_ms - seen_ms <= options_.worker_active_ms) break;
    ++inactive;
  }
  stats.workers_active = static_cast<int>(workers_by_seen_.size()) - inactive;
  stats.leases_expired = leases_expired_;
  stats.results_dropped = results_dropped_;
  stats.results_accepted = results_accepted_;
  stats.leases_issued = leases_issued_;
  stats.tasks_failed = tasks_failed_;
  stats.tasks_failed_by_code = tasks_failed_by_code_;
  stats.tasks_handed_back = tasks_handed_back_;
  stats.tasks_incompatible = tasks_incompatible_;
  return stats;
}

Scheduler::LeaseMap::iterator Scheduler::FindCurrent(const std::string& worker_id,
                                                     uint64_t lease_id) {
  const LeaseMap::iterator it = leases_.find(lease_id);
  if (it == leases_.end() || it->second.worker_id != worker_id) return leases_.end();
  return it;
}

Scheduler::LeaseInfo Scheduler::TakeLease(LeaseMap::iterator it) {
  LeaseInfo lease = std::move(it->second);
  const uint64_t lease_id = it->first;
  leases_.erase(it);
  deadlines_.erase({lease.deadline_ms, lease_id});
  Job& job = jobs_.at(lease.job_id);
  job.leases.erase(lease_id);
  GroupOf(job, lease.task).tasks[lease.task.second].lease_id.reset();
  return lease;
}

void Scheduler::Requeue(Job& job, TaskRef task) {
  job.pending.insert(task);
  UpdateReady(job);
}

std::optional<JobFailure> Scheduler::FailTask(LeaseMap::iterator it, const std::string& reason,
                                              bool handed_back, bool expired) {
  const LeaseInfo lease = TakeLease(it);
  Job& job = jobs_.at(lease.job_id);
  if (!handed_back) {
    std::optional<JobFailure> failure =
        expired ? CountExpiry(job, lease.task, lease.worker_id, reason)
                : CountFailure(job, lease.task, lease.worker_id, reason);
    if (failure) {
      RemoveJob(lease.job_id);
      return failure;
    }
  }
  Requeue(job, lease.task);
  return std::nullopt;
}

std::optional<JobFailure> Scheduler::CountFailure(Job& job, TaskRef task,
                                                  const std::string& worker_id,
                                                  const std::string& reason) {
  ++job.worker_failures[worker_id];
  job.last_failure = reason;
  GroupOf(job, task).tasks[task.second].failures.emplace_back(worker_id, reason);
  return TaskFailedTooOften(job, task);
}

std::optional<JobFailure> Scheduler::CountExpiry(Job& job, TaskRef task,
                                                 const std::string& worker_id,
                                                 const std::string& reason) {
  job.last_failure = reason;
  GroupOf(job, task).tasks[task.second].expired_on.insert(worker_id);
  return TaskFailedTooOften(job, task);
}

std::optional<JobFailure> Scheduler::TaskFailedTooOften(const Job& job, TaskRef task) const {
  const Task& t = GroupOf(job, task).tasks[task.second];
  std::vector<std::string> expired_only;
  for (const std::string& worker : t.expired_on) {
    const auto failed = [&](const auto& failure) { return failure.first == worker; };
    if (std::none_of(t.failures.begin(), t.failures.end(), failed)) expired_only.push_back(worker);
  }
  const size_t workers = t.failures.size() + expired_only.size();
  if (static_cast<int>(workers) < options_.max_task_failures) return std::nullopt;
  std::string why =
      absl::StrCat("tile group ", job.group_order[task.first].group_index, " samples [",
                   t.sample_begin, ", ", t.sample_end, ") failed on ", workers, " workers:");
  for (const auto& [worker, what] : t.failures) absl::StrAppend(&why, " ", worker, ": ", what, ";");
  for (const std::string& worker : expired_only) {
    absl::StrAppend(&why, " lease expired on worker ", worker, ";");
  }
  why.pop_back();
  return JobFailure{job.key.job_id, std::move(why)};
}

bool Scheduler::Excluded(const Job& job, const std::string& worker_id) const {
  const auto it = job.worker_failures.find(worker_id);
  return it != job.worker_failures.end() && it->second >= options_.max_worker_failures_per_job;
}

bool Scheduler::FailedAllRemaining(const Job& job, const std::string& worker_id) const {
  // Each failure is on a different task, so fewer failures than tasks left settles it, and
  // nobody has failed a task of an unopened group.
  const auto it = job.worker_failures.find(worker_id);
  if (it == job.worker_failures.end() || it->second < job.tasks_left) return false;
  if (job.next_group < job.group_order.size()) return false;
  for (const auto& [group_index, group] : job.groups) {
    for (const Task& task : group.tasks) {
      if (task.done) continue;
      const bool failed_here =
          std::any_of(task.failures.begin(), task.failures.end(),
                      [&](const auto& failure) { return failure.first == worker_id; });
      if (!failed_here) return false;
    }
  }
  return true;
}

std::optional<JobFailure> Scheduler::CheckStuck(const Job& job) const {
  if (job.tasks_left == 0) return std::nullopt;
  // Only workers that failed in this job can be unable to run it; if some active worker has
  // not, it can, and with ForgetInactiveWorkers() just run workers_by_seen_ is the active set.
  // Incompatible workers count neither way: with only them active the job waits for a
  // compatible one (a rolling upgrade under way), it does not fail.
  size_t active = 0;
  for (const auto& [seen_ms, worker_id] : workers_by_seen_) {
    active += job.incompatible_workers.contains(worker_id) ? 0 : 1;
  }
  if (active == 0 || active > job.worker_failures.size()) return std::nullopt;
  for (const auto& [seen_ms, worker_id] : workers_by_seen_) {
    if (job.incompatible_workers.contains(worker_id)) continue;
    if (!Excluded(job, worker_id) && !FailedAllRemaining(job, worker_id)) return std::nullopt;
  }
  return JobFailure{
      job.key.job_id,
      absl::StrCat(
          "no worker can run the job: every active worker (", active,
          ") is excluded from it after ", options_.max_worker_failures_per_job,
          " failures or has failed all its remaining tasks; last failure: ", job.last_failure)};
}

void Scheduler::UpdateReady(const Job& job) {
  if (job.pending.empty()) {
    ready_.erase(job.key);
  } else {
    ready_.insert(job.key);
  }
}

void Scheduler::Touch(const std::string& worker_id, int64_t now_ms) {
  if (quarantined_.contains(worker_id)) return;  // never active again
  auto [it, inserted] = worker_seen_ms_.try_emplace(worker_id, now_ms);
  if (!inserted) {
    if (it->second >= now_ms) return;  // a call from the past changes nothing
    workers_by_seen_.erase({it->second, worker_id});
    it->second = now_ms;
  }
  workers_by_seen_.insert({now_ms, worker_id});
}

void Scheduler::ForgetInactiveWorkers(int64_t now_ms) {
  // Forgetting them keeps the worker tables the size of the active farm despite churn.
  while (!workers_by_seen_.empty() &&
         now_ms - workers_by_seen_.begin()->first > options_.worker_active_ms) {
    worker_seen_ms_.erase(workers_by_seen_.begin()->second);
    workers_by_seen_.erase(workers_by_seen_.begin());
  }
}

}  // namespace pdsm
