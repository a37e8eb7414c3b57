#include "core/pipeline/bake_engine.h"

#include <algorithm>
#include <chrono>
#include <set>
#include <tuple>
#include <utility>

#include "absl/cleanup/cleanup.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "core/pipeline/result_digest.h"
#include "core/pipeline/unreached_tile.h"

namespace pdsm {
namespace {

constexpr int64_t kRateWindowMs = 60'000;

int64_t SteadyNowMs() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

EngineOptions WithDefaults(EngineOptions options) {
  if (!options.now_ms) options.now_ms = SteadyNowMs;
  return options;
}

// The tiles of `group` a caster may reach (plan.tile_has_casters; every tile when it is empty).
std::vector<int> CasterTiles(const BakePlan& plan, int group) {
  std::vector<int> tiles = plan.group(group).tiles;
  const std::vector<bool>& casters = plan.tile_has_casters;
  if (!casters.empty()) std::erase_if(tiles, [&](int t) { return !casters[t]; });
  return tiles;
}

// `direct` receives the tiles to do that no caster can reach: they need no task and are
// stored all lit at once. `work_tiles` counts the tiles given tasks. A group with none of its
// tiles done is listed without its tiles (JobSpec::tiles_of lists them when it opens): a job
// holds per-tile lists only for the groups it has open, and a resumed job's partly done ones.
JobSpec SchedulerSpec(const EngineJob& job, std::vector<int>* direct, int* work_tiles) {
  const PdsmHeader& header = job.plan->header;
  JobSpec spec;
  spec.job_id = job.job_id;
  spec.priority = job.priority;
  spec.sequence = job.sequence;
  spec.samples = header.samples;
  spec.samples_per_task = job.samples_per_task > 0 ? job.samples_per_task : header.samples;
  if (header.adaptive()) spec.adaptive_min_samples = std::max(1, header.adaptive_min_samples);
  spec.tiles_of = [plan = job.plan](int group) { return CasterTiles(*plan, group); };
  std::vector<bool> done(job.plan->tile_count(), false);
  for (int t : job.done_tiles) {
    if (t >= 0 && t < static_cast<int>(done.size())) done[t] = true;
  }
  const std::vector<bool>& casters = job.plan->tile_has_casters;
  *work_tiles = 0;
  for (int g = 0; g < job.plan->group_count(); ++g) {
    GroupWork work{g, {}};
    bool partly_done = false;
    for (int t : job.plan->group(g).tiles) {
      const bool reached = casters.empty() || casters[t];
      if (done[t]) {
        partly_done = partly_done || reached;
      } else if (reached) {
        work.tiles.push_back(t);
      } else {
        direct->push_back(t);
      }
    }
    if (work.tiles.empty()) continue;
    *work_tiles += static_cast<int>(work.tiles.size());
    if (!partly_done) work.tiles = {};  // tiles_of lists the same tiles
    spec.groups.push_back(std::move(work));
  }
  spec.groups.shrink_to_fit();  // held for the job's life: JobHeldBytes counts no spare room
  return spec;
}

}  // namespace

absl::Status JobOutput::StoreUnreachedTiles(const BakePlan& plan, const std::vector<int>& tiles) {
  for (int t : tiles) {
    if (absl::Status s = StoreTile(MakeUnreachedTile(plan, t).tile); !s.ok()) return s;
  }
  return absl::OkStatus();
}

absl::Status JobOutput::WithdrawTiles(const std::vector<int>& tile_indices) {
  return absl::UnimplementedError(
      absl::StrCat("this output cannot take back stored tiles (", tile_indices.size(),
                   " were fed by a quarantined worker): run it without verification"));
}

// An open group: its current stage and, per tile of that stage, the batches merged so far
// and (adaptive bakes) the tile's earlier stages. Results merge into it under its own mutex,
// outside the engine's; the report that brings the group's last result of a stage, or the
// last merge still running then, completes the stage. Its bytes in memory are counted in the
// engine's event_memory_bytes_ for as long as it lives.
struct BakeEngine::OpenGroup {
  OpenGroup(int stage, std::atomic<int64_t>* engine_bytes)
      : stage(stage), engine_bytes(engine_bytes) {}
  ~OpenGroup() { engine_bytes->fetch_sub(memory_bytes, std::memory_order_relaxed); }
  OpenGroup(const OpenGroup&) = delete;
  OpenGroup& operator=(const OpenGroup&) = delete;

  const int stage;
  std::atomic<int64_t>* const engine_bytes;
  absl::Mutex mu;
  std::map<int, StageAccumulator> tiles ABSL_GUARDED_BY(mu);
  std::map<int, TileStageState> states ABSL_GUARDED_BY(mu);
  int64_t memory_bytes ABSL_GUARDED_BY(mu) = 0;     // of `tiles`, in engine_bytes too
  int merging ABSL_GUARDED_BY(mu) = 0;              // reports merging into it now
  bool stage_complete ABSL_GUARDED_BY(mu) = false;  // the stage's last result has come
};

// A job in progress. Every field but `spec`, `spill` and `ended` is guarded by
// BakeEngine::mu_ (the annotation cannot name another object's mutex); `ended` is also read
// without it, to drop heavy work early.
struct BakeEngine::Job {
  EngineJob spec;
  std::unique_ptr<EventSpill> spill;   // null: lists stay in memory
  std::map<int, OpenGroupPtr> groups;  // by group index, from a group's first result to its end
  int direct_left = 0;                 // tiles no caster reaches, not stored yet
  JobProgress progress;
  int output_calls = 0;  // JobOutput calls in flight
  struct DeferredEnd {
    JobEnd end;
    absl::Status status;
    JobProgress progress;
  };
  std::optional<DeferredEnd> deferred_end;
  std::atomic<bool> ended{false};
  bool finishing = false;  // every tile is stored and Finish is on its way: nothing is redone

  // Verification (scheduler.verify_fraction > 0) only: what a quarantine must take back.
  std::map<int, std::set<std::string>> contributors;  // group -> workers merged since it started
  std::map<int, int64_t> merged_samples;  // group -> samples_done its merged results added
  std::set<int> tainted;                  // open groups to start over when their stage completes
  // What a group's stored tiles added to `progress`, by group index, and which tiles are
  // stored, by tile index: a group is withdrawn whole (ForgetGroup gets every tile it was
  // given work for), so sums per group suffice, and a job holds a bit per tile.
  struct StoredSums {
    int tiles = 0;                // added to tiles_done
    int all_lit = 0;              // added to tiles_all_lit
    int64_t tile_samples = 0;     // added to tile_samples_total
    int64_t samples_skipped = 0;  // added to samples_done
  };
  std::vector<StoredSums> stored_sums;
  std::vector<bool> stored;
};

int64_t BakeEngine::JobHeldBytes(int64_t tiles, int64_t groups, int64_t groups_with_work) {
  // Per tile: its stored bit (a byte's worth, rounded up). Per group: its Job::StoredSums;
  // per group with work, its GroupWork (a list of its tiles only while it is open, or partly
  // done before a restart: not counted). The rest of a job, its ids, map nodes and
  // scheduler entries, measured 3.4-4.1 KB (JobMemoryTest, 2026-12-06): glibc's placement moves
  // it by a kilobyte with what the process allocated and freed before.
  constexpr int64_t kJobFixedBytes = 5120;
  return int64_t{sizeof(Job)} + kJobFixedBytes + (tiles + 7) / 8 +
         groups * int64_t{sizeof(Job::StoredSums)} + groups_with_work * int64_t{sizeof(GroupWork)};
}

BakeEngine::BakeEngine(EngineOptions options)
    : options_(WithDefaults(std::move(options))),
      started_ms_(options_.now_ms()),
      scheduler_(options_.scheduler) {}

BakeEngine::~BakeEngine() = default;

BakeEngine::JobPtr BakeEngine::FindJob(const std::string& job_id) const {
  const auto it = jobs_.find(job_id);
  return it == jobs_.end() ? nullptr : it->second;
}

int64_t BakeEngine::TasksTotal(const Job& job) const {
  return job.progress.tasks_done + scheduler_.TasksLeft(job.spec.job_id).value_or(0);
}

absl::Status BakeEngine::AddJob(EngineJob spec) {
  if (!spec.plan || !spec.output) {
    return absl::InvalidArgumentError(
        absl::StrCat("job ", spec.job_id, ": a job needs a plan and an output"));
  }
  auto job = std::make_shared<Job>();
  std::vector<int> direct;
  int work_tiles = 0;
  const JobSpec scheduled = SchedulerSpec(spec, &direct, &work_tiles);
  // Read once: a resumed job's list of them is not kept.
  spec.done_tiles = std::vector<int>();
  job->direct_left = static_cast<int>(direct.size());
  JobProgress& p = job->progress;
  p.tiles_total = spec.plan->tile_count();
  p.tiles_done = p.tiles_total - work_tiles - job->direct_left;
  p.samples_total = int64_t{spec.plan->header.samples} * p.tiles_total;
  p.samples_done = int64_t{spec.plan->header.samples} * p.tiles_done;
  p.samples_at_add = p.samples_done;
  p.added_ms = options_.now_ms();
  p.started = spec.started;
  if (options_.scheduler.verify_fraction > 0) {
    job->stored.resize(spec.plan->tile_count());
    job->stored_sums.resize(spec.plan->group_count());
  }
  job->spec = std::move(spec);
  if (!options_.spill_dir.empty()) {
    job->spill = std::make_unique<EventSpill>(options_.spill_dir, options_.fs);
  }
  bool complete = false;
  {
    absl::MutexLock lock(&mu_);
    if (jobs_.contains(job->spec.job_id)) {
      return absl::AlreadyExistsError(
          absl::StrCat("job ", job->spec.job_id, " is already in progress"));
    }
    scheduler_.AddJob(scheduled);
    jobs_[job->spec.job_id] = job;
    p.tasks_total = TasksTotal(*job);
    complete = job->direct_left == 0 && scheduler_.JobComplete(job->spec.job_id);
    job->finishing = complete;
    changed_.SignalAll();
  }
  if (!direct.empty()) {
    options_.executor([this, job, d = std::move(direct)] { StoreUnreachedTiles(job, d); });
  } else if (complete) {
    options_.executor([this, job] { FinishJob(job); });
  }
  return absl::OkStatus();
}

void BakeEngine::StoreUnreachedTiles(const JobPtr& job, const std::vector<int>& tiles) {
  // In batches, so that a cancel stops a world of 2^18 empty tiles between two of them.
  constexpr size_t kBatch = 4096;
  const BakePlan& plan = *job->spec.plan;
  // Every unreached tile of a plan counts the same (adaptive: converged at the pilot).
  const UnreachedTile sample = MakeUnreachedTile(plan, tiles.front());
  const int64_t tile_samples = sample.tile_samples > 0 ? sample.tile_samples : plan.header.samples;
  for (size_t begin = 0; begin < tiles.size(); begin += kBatch) {
    const std::vector<int> batch(
        tiles.begin() + static_cast<ptrdiff_t>(begin),
        tiles.begin() + static_cast<ptrdiff_t>(std::min(tiles.size(), begin + kBatch)));
    if (!BeginOutputCall(job)) return;
    const absl::Status stored = job->spec.output->StoreUnreachedTiles(plan, batch);
    EndOutputCall(job);
    if (!stored.ok()) {
      return End(job, JobEnd::kFailed,
                 absl::Status(stored.code(),
                              absl::StrCat("storing ", batch.size(),
                                           " tiles no caster reaches: ", stored.message())));
    }
    if (!CommitTiles(job)) return;
    absl::MutexLock lock(&mu_);
    if (job->ended) return;
    const int n = static_cast<int>(batch.size());
    JobProgress& p = job->progress;
    job->direct_left -= n;
    p.tiles_done += n;
    p.tiles_all_lit += n;
    p.tiles_without_task += n;
    // What their tasks would have reported, and the samples they never needed.
    p.samples_done += int64_t{n} * (tile_samples + sample.samples_skipped);
    p.tile_samples_total += int64_t{n} * tile_samples;
  }
  bool complete = false;
  {
    absl::MutexLock lock(&mu_);
    if (job->ended) return;
    complete = job->direct_left == 0 && scheduler_.JobComplete(job->spec.job_id);
    job->finishing = complete;
  }
  if (complete) FinishJob(job);
}

std::optional<TaskLease> BakeEngine::Lease(const std::string& worker_id, absl::Duration wait) {
  const absl::Time deadline = absl::Now() + wait;
  JobPtr first_lease_of;
  std::optional<TaskLease> lease;
  {
    absl::MutexLock lock(&mu_);
    for (;;) {
      lease = scheduler_.Lease(worker_id, options_.now_ms());
      if (lease || jobs_.empty() || wait <= absl::ZeroDuration()) break;
      if (changed_.WaitWithDeadline(&mu_, deadline)) break;  // timed out
    }
    if (!lease) return std::nullopt;
    const JobPtr job = FindJob(lease->job_id);
    if (job && !job->progress.started) {
      job->progress.started = true;
      ++job->output_calls;  // Started() below counts as a call in flight
      first_lease_of = job;
    }
  }
  if (first_lease_of) {
    first_lease_of->spec.output->Started();
    EndOutputCall(first_lease_of);
  }
  return lease;
}

absl::StatusOr<int64_t> BakeEngine::Extend(const std::string& worker_id, uint64_t lease_id) {
  absl::MutexLock lock(&mu_);
  return scheduler_.Extend(worker_id, lease_id, options_.now_ms());
}

std::optional<TaskLease> BakeEngine::FindLease(uint64_t lease_id) const {
  absl::MutexLock lock(&mu_);
  return scheduler_.FindLease(lease_id);
}

bool BakeEngine::Report(const std::string& worker_id, uint64_t lease_id,
                        std::vector<TileEvents> events) {
  // A verified task's result is hashed outside the lock (it may be large); a lease that changes
  // meanwhile is found out by Complete.
  std::string digest;
  bool verify = false;
  {
    absl::MutexLock lock(&mu_);
    const std::optional<TaskLease> lease = scheduler_.FindLease(lease_id);
    verify = lease && lease->verify;
  }
  if (verify) digest = ResultDigest(events);

  JobPtr job;
  OpenGroupPtr group;         // merged into
  OpenGroupPtr complete_now;  // its stage completes through this result, with no merge
  int group_index = 0;
  ResultOutcome outcome;
  std::optional<JobFailure> failure;
  Withdrawals withdrawals;
  std::string quarantine_why;
  {
    absl::MutexLock lock(&mu_);
    const int64_t now = options_.now_ms();
    const std::optional<TaskLease> lease = scheduler_.FindLease(lease_id);
    if (lease && lease->tiles.size() != events.size()) {
      failure = scheduler_.Fail(worker_id, lease_id,
                                absl::StrCat("the result holds ", events.size(),
                                             " tiles' events for a task of ", lease->tiles.size()),
                                /*handed_back=*/false, now, absl::StatusCode::kInvalidArgument);
      if (!failure) {
        changed_.SignalAll();  // the task is pending again
        return false;
      }
    } else {
      outcome = scheduler_.Complete(worker_id, lease_id, now, digest);
      failure = outcome.failure;
      if (!failure && outcome.kind == ResultOutcome::kDropped) return false;
    }
    if (failure) {
      job = FindJob(failure->job_id);
    } else {
      job = FindJob(outcome.job_id);
      if (!job) return false;  // cannot happen: an ended job's leases are gone
      int64_t event_count = 0;
      for (const TileEvents& e : events) event_count += static_cast<int64_t>(e.events.size());
      recent_results_.emplace_back(now, event_count);
      ForgetOldRates(now);
      group_index = outcome.group_index;
      if (outcome.merge) {
        JobProgress& p = job->progress;
        ++p.tasks_done;
        const int64_t samples = int64_t{outcome.sample_end - outcome.sample_begin} *
                                static_cast<int64_t>(outcome.tiles.size());
        p.samples_done += samples;
        if (options_.scheduler.verify_fraction > 0) {
          job->contributors[group_index].insert(worker_id);
          job->merged_samples[group_index] += samples;
        }
        OpenGroupPtr& slot = job->groups[group_index];
        if (!slot) slot = std::make_shared<OpenGroup>(0, &event_memory_bytes_);
        group = slot;
        absl::MutexLock group_lock(&group->mu);
        ++group->merging;
        if (outcome.kind == ResultOutcome::kStageComplete) {
          group->stage_complete = true;
          job->groups.erase(group_index);
        }
      } else if (outcome.kind == ResultOutcome::kStageComplete) {
        absl::StatusOr<OpenGroupPtr> completed = CompleteWithoutMerge(job, outcome);
        if (completed.ok()) {
          complete_now = *std::move(completed);
        } else {
          failure = JobFailure{outcome.job_id, std::string(completed.status().message())};
        }
      }
      if (!outcome.quarantined.empty()) {
        withdrawals = Recompute(outcome.quarantined, &quarantine_why);
        quarantine_why = absl::StrCat(
            "its result for job ", outcome.job_id, ", tile group ", outcome.group_index,
            ", samples [", outcome.sample_begin, ", ", outcome.sample_end,
            ") differs from the one two other workers agree on; ", quarantine_why);
      }
    }
    changed_.SignalAll();
  }
  Withdraw(withdrawals);
  if (options_.on_quarantine) {
    for (const std::string& worker : outcome.quarantined) {
      options_.on_quarantine(worker, quarantine_why);
    }
  }
  if (failure) {
    if (job) End(job, JobEnd::kFailed, absl::AbortedError(failure->reason));
    return false;
  }
  if (complete_now) {
    options_.executor(
        [this, job, group_index, complete_now] { CompleteStage(job, group_index, complete_now); });
  }
  if (!group) return true;
  const absl::Status merged =
      MergeResult(*job, *group, outcome.sample_begin, outcome.tiles, std::move(events));
  bool complete = false;
  {
    absl::MutexLock group_lock(&group->mu);
    complete = --group->merging == 0 && group->stage_complete;
  }
  if (!merged.ok()) {
    End(job, JobEnd::kFailed, merged);
  } else if (complete) {
    options_.executor([this, job, group_index, group] { CompleteStage(job, group_index, group); });
  }
  return true;
}

absl::StatusOr<BakeEngine::OpenGroupPtr> BakeEngine::CompleteWithoutMerge(
    const JobPtr& job, const ResultOutcome& outcome) {
  const auto it = job->groups.find(outcome.group_index);
  // Every task's first result was merged, so its group is here until its stage completes; if
  // not, the stage would never complete and the job would hang: it fails instead.
  if (it == job->groups.end()) {
    return absl::InternalError(absl::StrCat("tile group ", outcome.group_index,
                                            ": its stage completed with no result merged"));
  }
  OpenGroupPtr group = it->second;
  job->groups.erase(it);
  absl::MutexLock group_lock(&group->mu);
  group->stage_complete = true;
  // Otherwise the last merge running into it completes it.
  return group->merging == 0 ? group : nullptr;
}

BakeEngine::Withdrawals BakeEngine::Recompute(const std::vector<std::string>& workers,
                                              std::string* summary) {
  Withdrawals withdrawals;
  int groups = 0, jobs = 0;
  std::vector<std::string> kept;
  for (const auto& [job_id, job] : jobs_) {
    std::vector<int> fed;
    for (const auto& [group_index, contributors] : job->contributors) {
      for (const std::string& worker : workers) {
        if (contributors.contains(worker)) {
          fed.push_back(group_index);
          break;
        }
      }
    }
    if (fed.empty()) continue;
    if (job->finishing) {
      kept.push_back(job_id);  // its file is being written: too late to take anything back
      continue;
    }
    ++jobs;
    groups += static_cast<int>(fed.size());
    std::vector<int> withdrawn;
    for (int group_index : fed) {
      if (std::optional<std::vector<int>> tiles = scheduler_.RequeueGroup(job_id, group_index)) {
        const std::vector<int> stored = ForgetGroup(*job, group_index, *tiles);
        withdrawn.insert(withdrawn.end(), stored.begin(), stored.end());
      } else {
        job->tainted.insert(group_index);  // open: CompleteStage starts it over
      }
    }
    job->progress.tasks_total = TasksTotal(*job);
    if (!withdrawn.empty()) withdrawals.emplace_back(job, std::move(withdrawn));
  }
  *summary =
      absl::StrCat("what it fed is computed again: ", groups, " tile groups of ", jobs, " jobs");
  if (!kept.empty()) {
    absl::StrAppend(summary,
                    "; jobs already being written keep its results: ", absl::StrJoin(kept, ", "));
  }
  return withdrawals;
}

std::vector<int> BakeEngine::ForgetGroup(Job& job, int group_index, const std::vector<int>& tiles) {
  JobProgress& p = job.progress;
  p.samples_done -= job.merged_samples[group_index];
  job.merged_samples.erase(group_index);
  job.contributors.erase(group_index);
  std::vector<int> stored;
  for (int t : tiles) {
    if (t < 0 || t >= static_cast<int>(job.stored.size()) || !job.stored[t]) continue;
    job.stored[t] = false;
    stored.push_back(t);
  }
  if (group_index >= 0 && group_index < static_cast<int>(job.stored_sums.size())) {
    Job::StoredSums& sums = job.stored_sums[group_index];
    p.tiles_done -= sums.tiles;
    p.tiles_all_lit -= sums.all_lit;
    p.tile_samples_total -= sums.tile_samples;
    p.samples_done -= sums.samples_skipped;
    p.tiles_recomputed += sums.tiles;
    sums = {};
  }
  return stored;
}

void BakeEngine::Withdraw(const Withdrawals& withdrawals) {
  for (const auto& [job, tiles] : withdrawals) {
    if (!BeginOutputCall(job)) continue;
    const absl::Status withdrawn = job->spec.output->WithdrawTiles(tiles);
    EndOutputCall(job);
    if (!withdrawn.ok()) {
      End(job, JobEnd::kFailed,
          absl::Status(withdrawn.code(),
                       absl::StrCat("taking back ", tiles.size(),
                                    " tiles to recompute: ", withdrawn.message())));
    }
  }
}

absl::Status BakeEngine::MergeResult(Job& job, OpenGroup& group, int sample_begin,
                                     const std::vector<int>& tiles,
                                     std::vector<TileEvents> events) {
  if (job.ended) return absl::OkStatus();  // nobody will read the lists
  absl::MutexLock lock(&group.mu);
  int64_t grown = 0;
  for (size_t i = 0; i < tiles.size(); ++i) {
    auto [it, added] = group.tiles.try_emplace(tiles[i], job.spec.plan->header, group.stage);
    grown += it->second.Add(sample_begin, std::move(events[i]));
  }
  group.memory_bytes += grown;
  const int64_t held = event_memory_bytes_.fetch_add(grown, std::memory_order_relaxed) + grown;
  if (!job.spill || held <= options_.event_memory_budget_bytes) return absl::OkStatus();
  // Over budget: this group's lists go to the scratch file. Its batches arrive together (a
  // task covers the whole group), so its lists are the ones growing.
  int64_t spilled = 0;
  absl::Status status;
  for (auto& [tile, accumulator] : group.tiles) {
    const int64_t before = accumulator.MemoryBytes();
    status = accumulator.Spill(job.spill.get());
    if (!status.ok()) break;
    spilled += before - accumulator.MemoryBytes();
  }
  group.memory_bytes -= spilled;
  event_memory_bytes_.fetch_sub(spilled, std::memory_order_relaxed);
  if (!status.ok()) {
    return absl::Status(status.code(),
                        absl::StrCat("moving event lists out of memory: ", status.message()));
  }
  return absl::OkStatus();
}

void BakeEngine::CompleteStage(const JobPtr& job, int group_index, const OpenGroupPtr& group) {
  if (job->ended) return;  // cancelled or failed while queued
  {
    // A quarantined worker fed the group: nothing of this stage is stored, `group` and its lists
    // go, and the tiles it stored in earlier stages are taken back.
    bool tainted = false, restarted = false;
    std::vector<int> withdrawn;
    {
      absl::MutexLock lock(&mu_);
      tainted = job->tainted.contains(group_index);
      if (tainted) restarted = RestartTainted(*job, group_index, &withdrawn);
      changed_.SignalAll();
    }
    if (tainted) {
      if (!restarted) {
        return End(job, JobEnd::kFailed,
                   absl::InternalError(
                       absl::StrCat("tile group ", group_index, ": could not start it over")));
      }
      if (!withdrawn.empty()) Withdraw({{job, std::move(withdrawn)}});
      return;
    }
  }
  const PdsmHeader& header = job->spec.plan->header;
  auto next = std::make_shared<OpenGroup>(group->stage + 1, &event_memory_bytes_);
  std::vector<int> next_tiles;
  // The lists leave the group (no merge is left to touch it), so that storing tiles, which
  // takes the engine's lock, never runs under the group's. The engine's count drops as each
  // tile's lists are taken, and for the rest if this ends early.
  std::map<int, StageAccumulator> tiles;
  std::map<int, TileStageState> states;
  int64_t held = 0;
  {
    absl::MutexLock group_lock(&group->mu);
    tiles.swap(group->tiles);
    states.swap(group->states);
    held = std::exchange(group->memory_bytes, 0);
  }
  absl::Cleanup release_rest = [&] {
    event_memory_bytes_.fetch_sub(held, std::memory_order_relaxed);
  };
  bool stored_any = false;
  for (auto& [tile, accumulator] : tiles) {
    TileStageState state;
    state.stage = group->stage;
    if (auto it = states.find(tile); it != states.end()) state = std::move(it->second);
    const int64_t tile_bytes = accumulator.MemoryBytes();
    std::vector<TileParts> ranges = accumulator.TakeRanges();
    held -= tile_bytes;
    event_memory_bytes_.fetch_sub(tile_bytes, std::memory_order_relaxed);
    absl::StatusOr<StageVerdict> verdict =
        JudgeStage(header, std::move(state), std::move(ranges), job->spill.get());
    if (!verdict.ok()) return FailReadingBack(job, tile, verdict.status());
    if (verdict->done) {
      if (!StoreTile(job, tile, *std::move(verdict))) return;
      stored_any = true;
    } else {
      next_tiles.push_back(tile);
      absl::MutexLock next_lock(&next->mu);
      next->states[tile] = std::move(verdict->next);
    }
  }
  if (stored_any && !CommitTiles(job)) return;
  bool complete = false, queued = true;
  std::vector<int> withdrawn;  // stored above, but a quarantine tainted the group meanwhile
  {
    absl::MutexLock lock(&mu_);
    if (job->ended) return;
    if (job->tainted.contains(group_index)) {
      queued = RestartTainted(*job, group_index, &withdrawn);
    } else if (next_tiles.empty()) {
      scheduler_.GroupAssembled(job->spec.job_id, group_index);
      complete = job->direct_left == 0 && scheduler_.JobComplete(job->spec.job_id);
      job->finishing = complete;
    } else {
      queued = scheduler_.AddStage(job->spec.job_id, group_index, next_tiles);
      job->progress.tasks_total = TasksTotal(*job);
      if (queued) job->groups[group_index] = std::move(next);
    }
    changed_.SignalAll();
  }
  if (!queued) {
    // A group left open would hold its slot and the job would never end: fail it loudly.
    return End(job, JobEnd::kFailed,
               absl::InternalError(absl::StrCat("tile group ", group_index,
                                                ": its next stage could not be queued")));
  }
  if (!withdrawn.empty()) Withdraw({{job, std::move(withdrawn)}});
  if (complete) FinishJob(job);
}

bool BakeEngine::RestartTainted(Job& job, int group_index, std::vector<int>* withdrawn) {
  job.tainted.erase(group_index);
  const std::optional<std::vector<int>> tiles =
      scheduler_.RestartGroup(job.spec.job_id, group_index);
  if (!tiles) return false;
  *withdrawn = ForgetGroup(job, group_index, *tiles);
  job.groups[group_index] = std::make_shared<OpenGroup>(0, &event_memory_bytes_);
  job.progress.tasks_total = TasksTotal(job);
  return true;
}

void BakeEngine::FailReadingBack(const JobPtr& job, int tile_index, const absl::Status& status) {
  End(job, JobEnd::kFailed,
      absl::Status(
          status.code(),
          absl::StrCat("tile ", tile_index, ": reading its event lists back: ", status.message())));
}

bool BakeEngine::CommitTiles(const JobPtr& job) {
  if (!BeginOutputCall(job)) return false;
  const absl::Status committed = job->spec.output->CommitTiles();
  EndOutputCall(job);
  if (!committed.ok()) {
    End(job, JobEnd::kFailed,
        absl::Status(committed.code(), absl::StrCat("storing tiles: ", committed.message())));
    return false;
  }
  return true;
}

bool BakeEngine::StoreTile(const JobPtr& job, int tile_index, StageVerdict verdict) {
  AssemblyStats stats;
  absl::StatusOr<PdsmTile> tile = AssemblePlanTile(*job->spec.plan, verdict.events,
                                                   job->spill.get(), verdict.tile_samples, &stats);
  verdict.events = TileParts{};
  if (!tile.ok()) {
    FailReadingBack(job, tile_index, tile.status());
    return false;
  }
  if (!BeginOutputCall(job)) return false;
  const absl::Status stored = job->spec.output->StoreTile(*tile);
  EndOutputCall(job);
  if (!stored.ok()) {
    End(job, JobEnd::kFailed,
        absl::Status(stored.code(),
                     absl::StrCat("storing tile ", tile_index, ": ", stored.message())));
    return false;
  }
  absl::MutexLock lock(&mu_);
  if (job->ended) return false;
  JobProgress& p = job->progress;
  ++p.tiles_done;
  if (tile->vertices.empty()) ++p.tiles_all_lit;
  p.samples_done += verdict.samples_skipped;
  const int64_t tile_samples =
      verdict.tile_samples > 0 ? verdict.tile_samples : job->spec.plan->header.samples;
  p.tile_samples_total += tile_samples;
  if (tile_index >= 0 && tile_index < static_cast<int>(job->stored.size())) {
    job->stored[tile_index] = true;
    Job::StoredSums& sums = job->stored_sums[job->spec.plan->GroupOfTile(tile_index)];
    ++sums.tiles;
    if (tile->vertices.empty()) ++sums.all_lit;
    sums.tile_samples += tile_samples;
    sums.samples_skipped += verdict.samples_skipped;
  }
  // Every spill of a tile's lists comes before it is stored, so the last tile's count is final.
  if (job->spill) p.spilled_bytes = job->spill->bytes_written();
  p.assembly.Add(stats);
  return true;
}

void BakeEngine::FinishJob(const JobPtr& job) {
  if (!BeginOutputCall(job)) return;
  const absl::Status finished = job->spec.output->Finish();
  if (finished.ok()) {
    absl::MutexLock lock(&mu_);
    if (!job->ended) {
      job->ended = true;
      jobs_.erase(job->spec.job_id);
      scheduler_.RemoveJob(job->spec.job_id);
      job->deferred_end = Job::DeferredEnd{JobEnd::kSucceeded, absl::OkStatus(), job->progress};
      changed_.SignalAll();
    }
  }
  EndOutputCall(job);  // calls Ended: kSucceeded, or what a cancel that won the race deferred
  if (!finished.ok()) {
    End(job, JobEnd::kFailed,
        absl::Status(finished.code(), absl::StrCat("writing the PDSM: ", finished.message())));
  }
}

bool BakeEngine::BeginOutputCall(const JobPtr& job) {
  absl::MutexLock lock(&mu_);
  if (job->ended) return false;
  ++job->output_calls;
  return true;
}

void BakeEngine::EndOutputCall(const JobPtr& job) {
  std::optional<Job::DeferredEnd> end;
  {
    absl::MutexLock lock(&mu_);
    if (--job->output_calls == 0 && job->deferred_end) {
      end = std::move(job->deferred_end);
      job->deferred_end.reset();
    }
  }
  if (end) job->spec.output->Ended(end->end, end->status, end->progress);
}

void BakeEngine::End(const JobPtr& job, JobEnd end, const absl::Status& status) {
  JobProgress progress;
  {
    absl::MutexLock lock(&mu_);
    if (job->ended) return;
    job->ended = true;
    jobs_.erase(job->spec.job_id);
    scheduler_.RemoveJob(job->spec.job_id);
    changed_.SignalAll();
    if (job->output_calls > 0) {
      job->deferred_end = Job::DeferredEnd{end, status, job->progress};
      return;
    }
    progress = job->progress;
  }
  job->spec.output->Ended(end, status, progress);
}

void BakeEngine::ReportFailure(const std::string& worker_id, uint64_t lease_id,
                               const absl::Status& status, bool handed_back) {
  JobPtr job;
  std::optional<JobFailure> failure;
  {
    absl::MutexLock lock(&mu_);
    const int64_t now = options_.now_ms();
    if (options_.task_failure_ends_job && !handed_back) {
      const std::optional<TaskLease> lease = scheduler_.FindLease(lease_id);
      if (lease) job = FindJob(lease->job_id);
      scheduler_.Fail(worker_id, lease_id, std::string(status.message()), /*handed_back=*/true,
                      now);
    } else {
      failure = scheduler_.Fail(worker_id, lease_id, std::string(status.message()), handed_back,
                                now, status.code());
      if (failure) job = FindJob(failure->job_id);
    }
    changed_.SignalAll();
  }
  if (!job) return;
  End(job, JobEnd::kFailed, failure ? absl::AbortedError(failure->reason) : status);
}

bool BakeEngine::ReportIncompatible(const std::string& worker_id, uint64_t lease_id) {
  absl::MutexLock lock(&mu_);
  const bool first = scheduler_.Incompatible(worker_id, lease_id, options_.now_ms());
  changed_.SignalAll();  // the task is pending again
  return first;
}

void BakeEngine::SignOff(const std::string& worker_id) {
  absl::MutexLock lock(&mu_);
  scheduler_.SignOff(worker_id);
}

bool BakeEngine::Quarantined(const std::string& worker_id) const {
  absl::MutexLock lock(&mu_);
  return scheduler_.Quarantined(worker_id);
}

void BakeEngine::Tick() {
  std::vector<std::pair<JobPtr, std::string>> failed;
  std::vector<std::tuple<JobPtr, int, OpenGroupPtr>> completed;
  {
    absl::MutexLock lock(&mu_);
    const int64_t now = options_.now_ms();
    for (JobFailure& f : scheduler_.Tick(now)) {
      if (JobPtr job = FindJob(f.job_id)) failed.emplace_back(job, std::move(f.reason));
    }
    for (const ResultOutcome& outcome : scheduler_.AcceptUnverifiable(now)) {
      const JobPtr job = FindJob(outcome.job_id);
      if (!job || outcome.kind != ResultOutcome::kStageComplete) continue;
      absl::StatusOr<OpenGroupPtr> group = CompleteWithoutMerge(job, outcome);
      if (!group.ok()) {
        failed.emplace_back(job, std::string(group.status().message()));
      } else if (*group) {
        completed.emplace_back(job, outcome.group_index, *std::move(group));
      }
    }
    ForgetOldRates(now);
    changed_.SignalAll();
  }
  for (const auto& [job, reason] : failed) End(job, JobEnd::kFailed, absl::AbortedError(reason));
  for (auto& [job, group_index, group] : completed) {
    // clang 14 cannot capture structured bindings: named copies instead.
    options_.executor(
        [this, j = job, g = group_index, open = group] { CompleteStage(j, g, open); });
  }
}

bool BakeEngine::Cancel(const std::string& job_id, const absl::Status& status) {
  return EndById(job_id, JobEnd::kCancelled, status);
}

bool BakeEngine::Fail(const std::string& job_id, const absl::Status& status) {
  return EndById(job_id, JobEnd::kFailed, status);
}

bool BakeEngine::EndById(const std::string& job_id, JobEnd end, const absl::Status& status) {
  JobPtr job;
  {
    absl::MutexLock lock(&mu_);
    job = FindJob(job_id);
  }
  if (!job) return false;
  End(job, end, status);
  return true;
}

std::shared_ptr<const BakePlan> BakeEngine::Plan(const std::string& job_id) const {
  absl::MutexLock lock(&mu_);
  const JobPtr job = FindJob(job_id);
  return job ? job->spec.plan : nullptr;
}

std::optional<JobProgress> BakeEngine::Progress(const std::string& job_id) const {
  absl::MutexLock lock(&mu_);
  const JobPtr job = FindJob(job_id);
  if (!job) return std::nullopt;
  return job->progress;
}

EngineStats BakeEngine::Stats() const {
  absl::MutexLock lock(&mu_);
  const int64_t now = options_.now_ms();
  EngineStats stats;
  stats.scheduler = scheduler_.Stats(now);
  for (const auto& [id, job] : jobs_) {
    ++(job->progress.started ? stats.jobs_started : stats.jobs_waiting);
  }
  int64_t events = 0, results = 0;
  for (const auto& [t, e] : recent_results_) {
    if (t >= now - kRateWindowMs) events += e, ++results;
  }
  const double window_s =
      static_cast<double>(std::clamp<int64_t>(now - started_ms_, 1, kRateWindowMs)) / 1000.0;
  stats.tasks_per_second = static_cast<double>(results) / window_s;
  stats.events_per_second = static_cast<double>(events) / window_s;
  return stats;
}

void BakeEngine::ForgetOldRates(int64_t now_ms) {
  while (!recent_results_.empty() && recent_results_.front().first < now_ms - kRateWindowMs) {
    recent_results_.pop_front();
  }
}

}  // namespace pdsm
