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

Scheduler::Scheduler(SchedulerOptions options)
    : options_(options), next_lease_id_(options.lease_id_base) {}

void Scheduler::AddJob(const JobSpec& spec) {
  Job& job = jobs_[spec.job_id];
  job.key = {spec.priority, spec.sequence, spec.job_id};
  // Nonsensical sizes become one sample per batch rather than tiles that never complete.
  job.samples = std::max(1, spec.samples);
  job.samples_per_task = std::max(1, spec.samples_per_task);
  job.adaptive_min_samples = std::clamp(spec.adaptive_min_samples, 0, job.samples);
  std::set<int> seen;
  for (const GroupWork& group : spec.groups) {
    // A repeat is the same group; a group with no tile has no work.
    if (!group.tiles.empty() && seen.insert(group.group_index).second) {
      job.group_order.push_back(group);
    }
  }
  job.groups_left = static_cast<int>(job.group_order.size());
  // Adaptive jobs: the tasks known so far (every group's pilot); later stages add theirs.
  job.tasks_left = int64_t{job.groups_left} * static_cast<int64_t>(StageBatches(job, 0).size());
  order_.insert(job.key);
}

std::optional<TaskLease> Scheduler::Lease(const std::string& worker_id, int64_t now_ms) {
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
  // since it is not excluded.
  for (const TaskRef& task : job.pending) {
    const std::vector<std::pair<std::string, std::string>>& failures =
        GroupOf(job, task).tasks[task.second].failures;
    const bool failed_here =
        std::any_of(failures.begin(), failures.end(),
                    [&](const auto& failure) { return failure.first == worker_id; });
    if (!failed_here) return Issue(job, task, worker_id, now_ms);
  }
  // A freshly opened group's first batch has failed on nobody.
  if (OpenGroup(job)) {
    return Issue(job, {static_cast<int>(job.next_group) - 1, 0}, worker_id, now_ms);
  }
  return std::nullopt;
}

bool Scheduler::OpenGroup(Job& job) {
  if (job.next_group >= job.group_order.size()) return false;
  const GroupWork& work = job.group_order[job.next_group];
  // The tile budget holds unless no group is open at all: a group larger than the budget
  // still gets its turn.
  const int tiles = static_cast<int>(work.tiles.size());
  if (tiles_open_ > 0 && tiles_open_ + tiles > options_.max_open_tiles) return false;
  const int position = static_cast<int>(job.next_group++);
  Group& group = job.groups[work.group_index];
  group.position = position;
  group.tiles = work.tiles;
  std::sort(group.tiles.begin(), group.tiles.end());
  group.tiles.erase(std::unique(group.tiles.begin(), group.tiles.end()), group.tiles.end());
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

ResultOutcome Scheduler::Complete(const std::string& worker_id, uint64_t lease_id, int64_t now_ms) {
  Touch(worker_id, now_ms);
  const LeaseMap::iterator it = FindCurrent(worker_id, lease_id);
  if (it == leases_.end()) {
    ++results_dropped_;
    return {};
  }
  const LeaseInfo lease = TakeLease(it);
  Job& job = jobs_.at(lease.job_id);
  Group& group = GroupOf(job, lease.task);
  group.tasks[lease.task.second].done = true;
  --group.tasks_left;
  --job.tasks_left;
  ++results_accepted_;

  ResultOutcome outcome;
  outcome.kind = group.tasks_left == 0 ? ResultOutcome::kStageComplete : ResultOutcome::kAccepted;
  outcome.job_id = lease.job_id;
  outcome.group_index = job.group_order[lease.task.first].group_index;
  outcome.tiles = group.tiles;
  outcome.sample_begin = group.tasks[lease.task.second].sample_begin;
  outcome.sample_end = group.tasks[lease.task.second].sample_end;
  return outcome;
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
    if (std::optional<JobFailure> failure = FailTask(it, reason, /*handed_back=*/false)) {
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
  }
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
                                              bool handed_back) {
  const LeaseInfo lease = TakeLease(it);
  Job& job = jobs_.at(lease.job_id);
  if (!handed_back) {
    std::optional<JobFailure> failure = CountFailure(job, lease.task, lease.worker_id, reason);
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
  std::vector<std::pair<std::string, std::string>>& failures =
      GroupOf(job, task).tasks[task.second].failures;
  failures.emplace_back(worker_id, reason);
  if (static_cast<int>(failures.size()) < options_.max_task_failures) return std::nullopt;

  const int64_t begin = GroupOf(job, task).tasks[task.second].sample_begin;
  const int64_t end = GroupOf(job, task).tasks[task.second].sample_end;
  std::string why =
      absl::StrCat("tile group ", job.group_order[task.first].group_index, " samples [", begin,
                   ", ", end, ") failed on ", failures.size(), " workers:");
  for (const auto& [worker, what] : failures) absl::StrAppend(&why, " ", worker, ": ", what, ";");
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
