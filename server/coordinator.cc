#include "server/coordinator.h"

#include <algorithm>
#include <chrono>
#include <filesystem>

#include <spdlog/spdlog.h>

#include "absl/strings/str_cat.h"
#include "core/scene/scene_loader.h"
#include "core/util/malloc_arenas.h"
#include "rpc/tile_events_codec.h"
#include "server/job_eta.h"

namespace pdsm {
namespace {

constexpr absl::Duration kTickInterval = absl::Milliseconds(250);
// gRPC clients refuse replies above 4 MiB unless told otherwise; leave room for the framing.
constexpr size_t kMaxListJobsBytes = (4 << 20) - (64 << 10);

// Job-store timestamps: wall-clock milliseconds since the epoch.
int64_t UnixNowMs() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

// The engine's clock (leases, rates, ETA): steady, so a clock step cannot expire every lease.
int64_t SteadyNowMs() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

bool IsTerminal(pdsm::v1::JobState state) {
  return state == pdsm::v1::SUCCEEDED || state == pdsm::v1::FAILED || state == pdsm::v1::CANCELLED;
}

EngineOptions MakeEngineOptions(const CoordinatorOptions& options, WorkQueue* pool) {
  EngineOptions e;
  e.scheduler.lease_ms = options.lease_ms;
  e.scheduler.max_task_failures = options.max_task_failures;
  e.scheduler.max_worker_failures_per_job = options.max_worker_failures;
  e.scheduler.verify_fraction = options.verify_fraction;
  e.scheduler.verify_seed = options.verify_seed;
  e.scheduler.max_open_tiles = options.max_open_tiles;
  // A fresh random base: results for a previous process's leases can never match.
  e.scheduler.lease_id_base = (std::stoull(RandomHex(4), nullptr, 16) << 32) | 1;
  e.executor = [pool](std::function<void()> work) { pool->Post(std::move(work)); };
  e.now_ms = SteadyNowMs;
  e.spill_dir = options.data_dir;
  e.event_memory_budget_bytes = options.event_memory_budget_bytes;
  e.fs = options.fs;
  e.on_quarantine = [](const std::string& worker_id, const std::string& why) {
    spdlog::error("worker {} quarantined by verification (it gets no more tasks): {}", worker_id,
                  why);
  };
  return e;
}

}  // namespace

Coordinator::Coordinator(const CoordinatorOptions& options)
    : options_(options),
      query_cache_(options.query_cache_bytes),
      started_ms_(SteadyNowMs()),
      engine_(MakeEngineOptions(options, &pool_)),
      budget_(options.limits.max_planned_bytes),
      // The ticker holds one thread for good; the others assemble.
      pool_(std::max(1, options.assembly_threads) + 1) {}

absl::StatusOr<std::unique_ptr<Coordinator>> Coordinator::Start(const CoordinatorOptions& options) {
  std::unique_ptr<Coordinator> c(new Coordinator(options));
  absl::StatusOr<std::unique_ptr<JobStore>> store = JobStore::Open(options.data_dir);
  if (!store.ok()) return store.status();
  c->store_ = *std::move(store);
  absl::StatusOr<std::unique_ptr<CoordinatorAssets>> assets =
      CoordinatorAssets::Open((std::filesystem::path(options.data_dir) / "assets").string(),
                              options.max_asset_bytes, options.fs);
  if (!assets.ok()) return assets.status();
  c->assets_ = *std::move(assets);
  if (absl::Status s = c->Resume(); !s.ok()) return s;
  c->pool_.Post([p = c.get()] { p->TickUntilStopped(); });
  return c;
}

Coordinator::~Coordinator() {
  // Every queued submit is answered: its caller's reactor waits for it.
  admission_.Wait();
  admission_.Stop();
  stopping_.Notify();
  // Unfinished work is safe to drop: everything not yet durable is redone on restart.
  pool_.Stop();
}

void Coordinator::TickUntilStopped() {
  while (!stopping_.WaitForNotificationWithTimeout(kTickInterval)) engine_.Tick();
}

// ---- Jobs: admission, resumption, ending -----------------------------------------------

absl::StatusOr<pdsm::v1::Job> Coordinator::SubmitBake(const pdsm::v1::SubmitBakeRequest& request) {
  if (absl::Status s = CheckSubmitRequest(request); !s.ok()) return s;
  absl::StatusOr<std::vector<PlannedLight>> plans =
      PlanJobLights(request.scene(), "scene", *assets_, &options_.limits);
  if (!plans.ok()) return plans.status();
  absl::StatusOr<JobRecord> record = NewJobRecord(request, *plans, UnixNowMs());
  if (!record.ok()) return record.status();
  bool created = false;
  absl::StatusOr<JobRecord> stored = store_->CreateJob(*record, &created);
  if (!stored.ok()) return stored.status();
  if (created) {
    const int64_t bytes = JobHeldBytes(*plans, request.scene());
    const double mib = static_cast<double>(bytes) / (1 << 20);
    if (plans->size() == 1) {
      spdlog::info(
          "job {}: submitted \"{}\", {}x{}, {} samples, {} tiles, priority {}, plans {:.1f} MiB",
          stored->job_id, stored->scene_name, stored->width, stored->height, stored->samples,
          stored->tiles_total, stored->priority, mib);
    } else {
      spdlog::info("job {}: submitted \"{}\", {} lights, {} tiles, priority {}, plans {:.1f} MiB",
                   stored->job_id, stored->scene_name, plans->size(), stored->tiles_total,
                   stored->priority, mib);
    }
    if (budget_.Admit({.job_id = stored->job_id,
                       .priority = stored->priority,
                       .sequence = stored->sequence,
                       .bytes = bytes})) {
      if (absl::Status s = ActivateCounted(*stored, {}, *std::move(plans)); !s.ok()) return s;
    } else {
      // Its plans are dropped here: it is planned again when its turn comes.
      spdlog::info("job {}: {}", stored->job_id, budget_.WaitingReason(stored->job_id));
    }
  }
  return GetJob(stored->job_id);
}

void Coordinator::SubmitBakeAsync(const pdsm::v1::SubmitBakeRequest* request,
                                  std::function<void(absl::StatusOr<pdsm::v1::Job>)> done) {
  admission_.Post([this, request, done = std::move(done)] {
    done(SubmitBake(*request));
    // Planning allocates the scene's meshes and each light's geometry, then frees them.
    ReturnFreeHeapToSystem();
  });
}

absl::Status Coordinator::ActivateCounted(const JobRecord& record,
                                          const std::vector<int>& done_tiles,
                                          std::vector<PlannedLight> plans) {
  if (absl::Status s = Activate(record, done_tiles, std::move(plans)); !s.ok()) {
    budget_.Release(record.job_id);
    return s;
  }
  if (budget_.Activated(record.job_id)) CancelRunning(record.job_id);
  return absl::OkStatus();
}

absl::Status Coordinator::Activate(const JobRecord& record, const std::vector<int>& done_tiles,
                                   std::vector<PlannedLight> plans) {
  pdsm::v1::Scene scene;
  if (!scene.ParseFromString(record.scene)) {
    return absl::DataLossError(absl::StrCat("job ", record.job_id, ": stored scene is corrupt"));
  }
  const std::string job_id = record.job_id;
  // A refined light's level (server/stored_job.h): planned from the stored scene, run as an
  // engine job beside the job's lights, with their priority and order.
  RefinementHooks refinement;
  refinement.threads = std::max(1, options_.assembly_threads);
  refinement.plan_level =
      [this, job_id](int light,
                     std::shared_ptr<const RefinedPixels> refined) -> absl::StatusOr<PlannedLight> {
    const std::shared_ptr<StoredJob> job = Active(job_id);
    if (!job) return absl::CancelledError(absl::StrCat("job ", job_id, " ended"));
    return PlanJobLightLevel(job->scene(), absl::StrCat("job ", job_id), *assets_, light,
                             *job->lights().at(light).plan, std::move(refined));
  };
  refinement.hold = [this, job_id](int64_t bytes) { budget_.Grow(job_id, bytes); };
  refinement.start_level = [this, priority = record.priority, sequence = record.sequence](
                               const std::string& engine_id, std::shared_ptr<const BakePlan> plan,
                               std::shared_ptr<JobOutput> output) {
    EngineJob spec;
    spec.job_id = engine_id;
    spec.priority = priority;
    spec.sequence = sequence;
    spec.samples_per_task = SamplesPerTask(*plan);
    spec.plan = std::move(plan);
    spec.started = true;  // the job is RUNNING already
    spec.output = std::move(output);
    return engine_.AddJob(std::move(spec));
  };
  auto job = std::make_shared<StoredJob>(
      store_.get(), options_.data_dir, record, std::move(scene), std::move(plans),
      [this](const std::string& id) { Forget(id); },
      [this, job_id](const absl::Status& why) { EndLights(job_id, why); }, options_.fs,
      std::move(refinement));
  absl::StatusOr<std::vector<int>> resumed = job->ResumeTiles(done_tiles);
  if (!resumed.ok()) {
    return absl::Status(resumed.status().code(),
                        absl::StrCat("job ", job_id, ": ", resumed.status().message()));
  }
  const std::vector<int>& done = *resumed;
  {
    absl::MutexLock lock(&mu_);
    active_[job_id] = job;
  }
  for (const JobLight& light : job->lights()) {
    EngineJob spec;
    spec.job_id = light.engine_id;
    spec.priority = record.priority;
    spec.sequence = record.sequence;
    spec.plan = light.plan;
    spec.samples_per_task = SamplesPerTask(*light.plan);
    // The light's range of the done tiles (ascending: JobStore::DoneTiles), in its own indices.
    const auto first = std::lower_bound(done.begin(), done.end(), light.tile_offset);
    const auto last = std::lower_bound(first, done.end(), light.tile_offset + light.tile_count());
    for (auto it = first; it != last; ++it) spec.done_tiles.push_back(*it - light.tile_offset);
    spec.started = record.state == pdsm::v1::RUNNING;
    spec.output = job->LightOutput(light.index);
    if (absl::Status added = engine_.AddJob(std::move(spec)); !added.ok()) {
      // Never for a fresh coordinator's ids. The lights added so far end; the others never
      // started, so the job is let go here.
      EndLights(job_id, added);
      Forget(job_id);
      return added;
    }
  }
  return absl::OkStatus();
}

int Coordinator::SamplesPerTask(const BakePlan& plan) const {
  return options_.samples_per_task > 0 ? options_.samples_per_task
                                       : std::clamp((plan.header.samples + 7) / 8, 1, 64);
}

void Coordinator::EndLights(const std::string& job_id, const absl::Status& why) {
  const std::shared_ptr<StoredJob> job = Active(job_id);
  if (!job) return;
  for (const std::string& id : job->EngineIds()) engine_.Fail(id, why);
}

absl::Status Coordinator::Resume() {
  absl::StatusOr<std::vector<JobRecord>> jobs = store_->UnfinishedJobs();
  if (!jobs.ok()) return jobs.status();
  for (const JobRecord& record : *jobs) {
    budget_.Enqueue({.job_id = record.job_id,
                     .priority = record.priority,
                     .sequence = record.sequence,
                     .bytes = -1});
  }
  ActivateWaiting();
  ReturnFreeHeapToSystem();
  return absl::OkStatus();
}

void Coordinator::ActivateWaiting() {
  while (const std::optional<PlanBudget::Entry> next = budget_.TakeNext()) {
    const std::string& job_id = next->job_id;
    const std::string label = absl::StrCat("job ", job_id);
    absl::StatusOr<JobRecord> record = store_->GetJob(job_id);
    if (!record.ok() || IsTerminal(record->state)) {
      budget_.Release(job_id);
      continue;
    }
    // A job that cannot start fails, saying why; it must not keep the others waiting.
    const auto cannot = [&](const char* what, const absl::Status& why) {
      spdlog::error("job {}: {}: {}", job_id, what, std::string(why.message()));
      budget_.Release(job_id);
      EndUnstarted(job_id, pdsm::v1::FAILED,
                   absl::Status(why.code(), absl::StrCat(what, ": ", why.message())));
    };
    pdsm::v1::Scene scene;
    absl::StatusOr<std::vector<PlannedLight>> plans =
        scene.ParseFromString(record->scene)
            ? PlanJobLights(scene, label, *assets_, nullptr)
            : absl::DataLossError(absl::StrCat(label, ": stored scene is corrupt"));
    if (!plans.ok()) {
      cannot("cannot be planned", plans.status());
      continue;
    }
    absl::StatusOr<std::vector<int>> done = store_->DoneTiles(job_id);
    if (!done.ok()) {
      cannot("cannot read its finished tiles", done.status());
      continue;
    }
    switch (budget_.Planned(job_id, JobHeldBytes(*plans, scene))) {
      case PlanBudget::Verdict::kWait:
        spdlog::info("job {}: {}", job_id, budget_.WaitingReason(job_id));
        return;
      case PlanBudget::Verdict::kCancelled:
        EndUnstarted(job_id, pdsm::v1::CANCELLED, absl::CancelledError("cancelled by request"));
        continue;
      case PlanBudget::Verdict::kActivate:
        break;
    }
    if (absl::Status s = ActivateCounted(*record, *done, *std::move(plans)); !s.ok()) {
      cannot("cannot start", s);  // ActivateCounted released it already; again is harmless
      continue;
    }
    spdlog::info("job {}: running with {} of {} tiles done", job_id, done->size(),
                 record->tiles_total);
  }
}

void Coordinator::EndUnstarted(const std::string& job_id, pdsm::v1::JobState state,
                               const absl::Status& why) {
  if (absl::Status s = store_->SetState(job_id, state, std::string(why.message()), UnixNowMs());
      !s.ok()) {
    spdlog::error("job {}: cannot record it {}: {}", job_id, pdsm::v1::JobState_Name(state),
                  std::string(s.message()));
  }
}

std::shared_ptr<StoredJob> Coordinator::Active(const std::string& job_id) const {
  absl::MutexLock lock(&mu_);
  const auto it = active_.find(job_id);
  return it == active_.end() ? nullptr : it->second;
}

void Coordinator::Forget(const std::string& job_id) {
  {
    absl::MutexLock lock(&mu_);
    active_.erase(job_id);
  }
  budget_.Release(job_id);
  // Planning is heavy: on the admission thread, one plan at a time, as submits are.
  if (budget_.HasWaiting()) {
    admission_.Post([this] {
      ActivateWaiting();
      ReturnFreeHeapToSystem();
    });
  }
}

absl::StatusOr<pdsm::v1::Job> Coordinator::CancelJob(const std::string& job_id) {
  absl::StatusOr<JobRecord> record = store_->GetJob(job_id);
  if (!record.ok()) return record.status();
  if (!IsTerminal(record->state)) {
    switch (budget_.Cancel(job_id)) {
      case PlanBudget::CancelOutcome::kWasWaiting:
        spdlog::info("job {}: CANCELLED while it waited", job_id);
        EndUnstarted(job_id, pdsm::v1::CANCELLED, absl::CancelledError("cancelled by request"));
        break;
      case PlanBudget::CancelOutcome::kActivating:
        break;  // whoever is activating it cancels it (ActivateCounted, ActivateWaiting)
      case PlanBudget::CancelOutcome::kNotHere:
        CancelRunning(job_id);
        break;
    }
  }
  return GetJob(job_id);
}

void Coordinator::CancelRunning(const std::string& job_id) {
  const std::shared_ptr<StoredJob> job = Active(job_id);
  if (!job) return;
  const absl::Status why = absl::CancelledError("cancelled by request");
  bool cancelled = false;
  for (const std::string& id : job->EngineIds()) cancelled = engine_.Cancel(id, why) || cancelled;
  if (cancelled) job->RecordEnd(JobEnd::kCancelled, why);
}

// ---- Job views -------------------------------------------------------------------------

std::vector<std::optional<JobProgress>> Coordinator::LightsProgress(const StoredJob& job) const {
  std::vector<std::optional<JobProgress>> progress;
  for (const JobLight& light : job.lights()) {
    std::optional<JobProgress> p = engine_.Progress(light.engine_id);
    progress.push_back(p ? std::move(p) : job.LightEndProgress(light.index));
  }
  return progress;
}

std::optional<JobProgress> Coordinator::SumProgress(
    const std::vector<std::optional<JobProgress>>& lights) {
  std::optional<JobProgress> sum;
  for (const std::optional<JobProgress>& p : lights) {
    if (!p) continue;
    if (!sum) {
      sum = *p;
      continue;
    }
    sum->started = sum->started || p->started;
    sum->tiles_total += p->tiles_total;
    sum->tiles_done += p->tiles_done;
    sum->samples_total += p->samples_total;
    sum->samples_done += p->samples_done;
    sum->samples_at_add += p->samples_at_add;
    sum->added_ms = std::min(sum->added_ms, p->added_ms);
  }
  return sum;
}

std::vector<double> Coordinator::AddLightsProgress(
    const JobRecord& record, const std::vector<JobLightSize>& sizes, const StoredJob* active,
    const std::vector<std::optional<JobProgress>>& progress, pdsm::v1::Job* job) const {
  std::vector<double> level_etas;
  // An ended job of several lights: its done tiles, told apart by light.
  std::vector<int> done_tiles;
  if (sizes.size() > 1 && progress.empty() && record.state != pdsm::v1::SUCCEEDED) {
    if (absl::StatusOr<std::vector<int>> done = store_->DoneTiles(record.job_id); done.ok()) {
      done_tiles = *std::move(done);
    }
  }
  int offset = 0;
  int64_t samples_done = 0;
  for (size_t i = 0; i < sizes.size(); ++i) {
    const JobLightSize& size = sizes[i];
    pdsm::v1::LightProgress* light = job->add_lights();
    light->set_name(size.name);
    light->set_width(size.width);
    light->set_height(size.height);
    light->set_samples(size.samples);
    light->set_tiles_total(size.tiles);
    light->set_samples_total(int64_t{size.tiles} * size.samples);
    *light->mutable_bake() = size.bake;
    if (record.state == pdsm::v1::SUCCEEDED) {
      light->set_tiles_done(size.tiles);
      light->set_samples_done(light->samples_total());
    } else if (i < progress.size() && progress[i]) {
      light->set_tiles_done(progress[i]->tiles_done);
      light->set_samples_done(progress[i]->samples_done);
    } else {
      const int done =
          sizes.size() == 1
              ? record.tiles_done
              : static_cast<int>(std::count_if(done_tiles.begin(), done_tiles.end(), [&](int t) {
                  return t >= offset && t < offset + size.tiles;
                }));
      light->set_tiles_done(done);
      light->set_samples_done(int64_t{done} * size.samples);
    }
    if (active != nullptr && !active->ended() && i < active->lights().size()) {
      light->set_plan_fingerprint(active->lights()[i].fingerprint);
      const absl::StatusOr<StoredJob::LevelInfo> level = active->Level(static_cast<int>(i));
      const std::optional<JobProgress> p =
          level.ok() ? engine_.Progress(level->engine_id) : std::nullopt;
      if (p) {
        pdsm::v1::RefinementLevelProgress* out = light->mutable_refinement_level();
        out->set_factor(level->factor);
        out->set_pixels(level->pixels);
        out->set_tiles_total(p->tiles_total);
        out->set_tiles_done(p->tiles_done);
        out->set_samples_total(p->samples_total);
        out->set_samples_done(p->samples_done);
        out->set_progress(p->samples_total > 0 ? static_cast<double>(p->samples_done) /
                                                     static_cast<double>(p->samples_total)
                                               : 0.0);
        out->set_eta_seconds(RateEtaSeconds(*p, SteadyNowMs()));
        level_etas.push_back(out->eta_seconds());
      }
    }
    light->set_progress(light->samples_total() > 0 ? static_cast<double>(light->samples_done()) /
                                                         static_cast<double>(light->samples_total())
                                                   : 0.0);
    samples_done += light->samples_done();
    offset += size.tiles;
  }
  // An ended job's work over its lights' own samples (the record keeps the first light's).
  if (progress.empty() && sizes.size() > 1) job->set_samples_done(samples_done);
  return level_etas;
}

pdsm::v1::Job Coordinator::ToProto(const JobRecord& record) const {
  pdsm::v1::Job job;
  job.set_job_id(record.job_id);
  job.set_idempotency_key(record.idempotency_key);
  job.set_scene_name(record.scene_name);
  job.set_state(record.state);
  job.set_priority(record.priority);
  job.set_error(record.error);
  job.set_tiles_total(record.tiles_total);
  job.set_tiles_done(record.tiles_done);
  job.set_samples_total(record.samples_total);
  job.set_samples_done(record.state == pdsm::v1::SUCCEEDED
                           ? record.samples_total
                           : int64_t{record.tiles_done} * record.samples);
  job.set_created_unix_ms(record.created_unix_ms);
  job.set_updated_unix_ms(record.updated_unix_ms);
  job.set_pdsm_bytes(record.pdsm_bytes);
  job.set_tile_assemblies(record.tile_assemblies);
  job.set_width(record.width);
  job.set_height(record.height);
  job.set_samples(record.samples);
  job.set_eta_seconds(record.state == pdsm::v1::SUCCEEDED ? 0 : -1);
  // Each light's size and settings, and the first's as the job's: what a viewer needs to plan
  // the job's PDSM itself (ListJobs' records carry no scene).
  absl::StatusOr<std::vector<JobLightSize>> sizes = absl::NotFoundError("no scene");
  if (!record.scene.empty()) {
    sizes = JobLightSizes(record.scene, absl::StrCat("job ", record.job_id));
    if (sizes.ok()) {
      *job.mutable_bake() = sizes->at(0).bake;
    } else {
      spdlog::warn("{}", std::string(sizes.status().message()));
    }
  }
  const std::shared_ptr<StoredJob> active = Active(record.job_id);
  if (!active && record.state == pdsm::v1::QUEUED) {
    job.set_queued_reason(budget_.WaitingReason(record.job_id));
  }
  if (active && !active->ended()) job.set_plan_fingerprint(active->fingerprint());
  std::vector<std::optional<JobProgress>> light_progress;
  if (active && !IsTerminal(record.state)) {
    light_progress = LightsProgress(*active);
    if (const std::optional<JobProgress> p = SumProgress(light_progress)) {
      if (p->started) job.set_state(pdsm::v1::RUNNING);
      job.set_tiles_done(p->tiles_done);
      job.set_samples_done(p->samples_done);
      job.set_eta_seconds(RateEtaSeconds(*p, SteadyNowMs()));
    }
  }
  // Each light (GetJob and WatchJob: ListJobs' records carry no scene to size them from).
  if (sizes.ok()) {
    const std::vector<double> level_etas =
        AddLightsProgress(record, *sizes, active.get(), light_progress, &job);
    // Base maps baked, their levels running: the job is not done in 0 s.
    if (!level_etas.empty()) {
      job.set_eta_seconds(
          JobEtaSeconds(job.eta_seconds(), job.samples_done() >= job.samples_total(), level_etas));
    }
  }
  job.set_progress(job.samples_total() > 0
                       ? static_cast<double>(job.samples_done()) / job.samples_total()
                       : (job.state() == pdsm::v1::SUCCEEDED ? 1.0 : 0.0));
  return job;
}

absl::StatusOr<pdsm::v1::Job> Coordinator::GetJob(const std::string& job_id) {
  absl::StatusOr<JobRecord> record = store_->GetJob(job_id);
  if (!record.ok()) return record.status();
  return ToProto(*record);
}

absl::StatusOr<std::vector<pdsm::v1::Job>> Coordinator::ListJobs(int limit) {
  // The listing's records carry no scene blob: nothing here needs one.
  absl::StatusOr<std::vector<JobRecord>> records = store_->ListJobs(limit > 0 ? limit : 100);
  if (!records.ok()) return records.status();
  std::vector<pdsm::v1::Job> jobs;
  jobs.reserve(records->size());
  size_t bytes = 0;
  for (const JobRecord& r : *records) {
    pdsm::v1::Job job = ToProto(r);
    // The listing stops before it outgrows a client's default 4 MiB message limit.
    bytes += job.ByteSizeLong() + 8;
    if (bytes > kMaxListJobsBytes) break;
    jobs.push_back(std::move(job));
  }
  return jobs;
}

absl::StatusOr<std::string> Coordinator::PdsmPath(const std::string& job_id) {
  absl::StatusOr<JobRecord> record = store_->GetJob(job_id);
  if (!record.ok()) return record.status();
  if (record->state != pdsm::v1::SUCCEEDED) {
    return absl::FailedPreconditionError(absl::StrCat(
        "job ", job_id, " is ", pdsm::v1::JobState_Name(record->state), ", not SUCCEEDED"));
  }
  return JobPaths(options_.data_dir, job_id).pdsm;
}

absl::StatusOr<std::shared_ptr<StoredJob>> Coordinator::RunningJob(const std::string& job_id) {
  std::shared_ptr<StoredJob> job = Active(job_id);
  if (!job || job->ended()) {
    absl::StatusOr<JobRecord> record = store_->GetJob(job_id);
    if (!record.ok()) return record.status();
    return absl::FailedPreconditionError(absl::StrCat("job ", job_id, " is ",
                                                      pdsm::v1::JobState_Name(record->state),
                                                      ": its tiles are only served while it runs"));
  }
  return job;
}

absl::StatusOr<std::vector<int>> Coordinator::FinishedTiles(const std::string& job_id,
                                                            std::string_view light) {
  absl::StatusOr<std::shared_ptr<StoredJob>> job = RunningJob(job_id);
  if (!job.ok()) return job.status();
  absl::StatusOr<int> index = FindJobLight((*job)->lights(), light, job_id);
  if (!index.ok()) return index.status();
  return (*job)->FinishedTiles(*index);
}

absl::StatusOr<std::string> Coordinator::FinishedTileBytes(const std::string& job_id,
                                                           std::string_view light, int tile_index) {
  // The index is checked first, against the light's tiles as the stored scene sizes them: a
  // tile that can never exist is INVALID_ARGUMENT whatever the job's state.
  absl::StatusOr<JobRecord> record = store_->GetJob(job_id);
  if (!record.ok()) return record.status();
  absl::StatusOr<std::vector<JobLightSize>> sizes =
      JobLightSizes(record->scene, absl::StrCat("job ", job_id));
  if (!sizes.ok()) return sizes.status();
  int light_tiles = -1;
  for (const JobLightSize& size : *sizes) {
    if (sizes->size() == 1 || size.name == light) light_tiles = size.tiles;
  }
  if (light_tiles >= 0 && (tile_index < 0 || tile_index >= light_tiles)) {
    return absl::InvalidArgumentError(absl::StrCat("tile_index: ", tile_index, " is outside the ",
                                                   sizes->size() == 1 ? "job's" : "light's",
                                                   " tiles [0, ", light_tiles, ")"));
  }
  absl::StatusOr<std::shared_ptr<StoredJob>> job = RunningJob(job_id);
  if (!job.ok()) return job.status();
  absl::StatusOr<int> index = FindJobLight((*job)->lights(), light, job_id);
  if (!index.ok()) return index.status();
  return (*job)->FinishedTileBytes(*index, tile_index);
}

absl::StatusOr<QueryAnswer> Coordinator::Query(const std::string& job_id, std::string_view light,
                                               const std::vector<glm::dvec3>& points_world) {
  absl::StatusOr<std::string> path = PdsmPath(job_id);
  if (!path.ok()) return path.status();
  return query_cache_.Query(job_id, *path, light, points_world);
}

CoordinatorMetrics Coordinator::Metrics() {
  CoordinatorMetrics m;
  m.engine = engine_.Stats();
  absl::StatusOr<std::map<pdsm::v1::JobState, JobStore::StateTotals>> totals =
      store_->TotalsByState();
  if (totals.ok()) {
    m.jobs = *std::move(totals);
  } else {
    spdlog::warn("metrics: {}", std::string(totals.status().message()));
  }
  m.task_seconds = task_seconds_.Read();
  // The engine counts its jobs, one per light: count the jobs.
  m.engine.jobs_started = m.engine.jobs_waiting = 0;
  CountActiveJobs(&m.engine.jobs_started, &m.engine.jobs_waiting, &m.job_progress);
  m.uptime_seconds = static_cast<double>(SteadyNowMs() - started_ms_) / 1000.0;
  const PlanBudget::Usage planned = budget_.usage();
  m.planned_bytes = planned.held_bytes;
  m.max_planned_bytes = planned.limit_bytes;
  m.jobs_waiting_for_memory = planned.jobs_waiting;
  return m;
}

void Coordinator::CountActiveJobs(int* started, int* waiting,
                                  std::vector<std::pair<std::string, double>>* progress) const {
  std::vector<std::shared_ptr<StoredJob>> jobs;
  {
    absl::MutexLock lock(&mu_);
    for (const auto& [job_id, job] : active_) jobs.push_back(job);
  }
  for (const std::shared_ptr<StoredJob>& job : jobs) {
    if (job->ended()) continue;
    const std::optional<JobProgress> p = SumProgress(LightsProgress(*job));
    if (!p) continue;  // ended meanwhile
    ++*(p->started ? started : waiting);
    if (progress != nullptr && p->samples_total > 0) {
      progress->emplace_back(job->record().job_id, static_cast<double>(p->samples_done) /
                                                       static_cast<double>(p->samples_total));
    }
  }
}

pdsm::v1::Stats Coordinator::GetStats() {
  const EngineStats s = engine_.Stats();
  pdsm::v1::Stats stats;
  int started = 0, waiting = 0;
  CountActiveJobs(&started, &waiting, nullptr);
  const PlanBudget::Usage planned = budget_.usage();
  stats.set_jobs_running(started);
  stats.set_jobs_queued(waiting + planned.jobs_waiting);
  stats.set_jobs_waiting_for_memory(planned.jobs_waiting);
  stats.set_planned_bytes(planned.held_bytes);
  stats.set_max_planned_bytes(planned.limit_bytes);
  stats.set_tasks_pending(s.scheduler.tasks_pending);
  stats.set_tasks_leased(s.scheduler.tasks_leased);
  stats.set_tiles_in_flight(s.scheduler.tiles_open);
  stats.set_workers_active(s.scheduler.workers_active);
  stats.set_tasks_per_second(s.tasks_per_second);
  stats.set_events_per_second(s.events_per_second);
  stats.set_tasks_accepted(s.scheduler.results_accepted);
  stats.set_results_dropped(s.scheduler.results_dropped);
  stats.set_leases_expired(s.scheduler.leases_expired);
  stats.set_workers_incompatible(s.scheduler.workers_incompatible);
  stats.set_tasks_verified(s.scheduler.tasks_verified);
  stats.set_verification_mismatches(s.scheduler.verification_mismatches);
  stats.set_tasks_unverified(s.scheduler.tasks_unverified);
  stats.set_workers_quarantined(s.scheduler.workers_quarantined);
  stats.set_tasks_awaiting_verification(s.scheduler.tasks_awaiting_verification);
  stats.set_uptime_seconds(static_cast<double>(SteadyNowMs() - started_ms_) / 1000.0);
  return stats;
}

// ---- Worker API ------------------------------------------------------------------------

std::optional<pdsm::v1::Task> Coordinator::LeaseTask(const std::string& worker_id) {
  const std::optional<TaskLease> lease = engine_.Lease(worker_id);
  if (!lease) return std::nullopt;
  const std::optional<EngineJobOf> of = ParseEngineJobId(lease->job_id);
  const std::shared_ptr<StoredJob> job = of ? Active(of->job_id) : nullptr;
  spdlog::debug("job {} tile group {} ({} tiles): samples [{}, {}) leased to {} (lease {})",
                lease->job_id, lease->group_index, lease->tiles.size(), lease->sample_begin,
                lease->sample_end, worker_id, lease->lease_id);
  pdsm::v1::Task task;
  task.set_job_id(of ? of->job_id : lease->job_id);
  task.set_lease_id(lease->lease_id);
  task.set_group_index(lease->group_index);
  task.mutable_tile_indices()->Assign(lease->tiles.begin(), lease->tiles.end());
  task.set_sample_begin(lease->sample_begin);
  task.set_sample_end(lease->sample_end);
  task.set_lease_ms(options_.lease_ms);
  // Ended between the lease and here: the worker's result will be dropped.
  if (job && of->light < static_cast<int>(job->lights().size())) {
    const JobLight& light = job->lights()[of->light];
    task.set_light(light.name);
    task.set_plan_fingerprint(light.fingerprint);
    if (of->level) {
      task.set_refinement_level(true);
      absl::StatusOr<StoredJob::LevelInfo> level = job->Level(of->light);
      task.set_plan_fingerprint(level.ok() ? level->fingerprint : "");
    }
  }
  return task;
}

absl::StatusOr<int64_t> Coordinator::ExtendLease(const std::string& worker_id, uint64_t lease_id) {
  absl::StatusOr<int64_t> deadline = engine_.Extend(worker_id, lease_id);
  if (!deadline.ok()) return deadline.status();
  return options_.lease_ms;
}

absl::StatusOr<bool> Coordinator::ReportResult(
    const std::string& worker_id, uint64_t lease_id,
    const google::protobuf::RepeatedPtrField<pdsm::v1::TileEventsData>& tiles, double seconds) {
  const std::optional<TaskLease> lease = engine_.FindLease(lease_id);
  const std::shared_ptr<const BakePlan> plan = lease ? engine_.Plan(lease->job_id) : nullptr;
  if (!plan) {
    engine_.Report(worker_id, lease_id, {});  // counts the drop
    return false;
  }
  if (static_cast<size_t>(tiles.size()) != lease->tiles.size()) {
    return absl::InvalidArgumentError(absl::StrCat("tiles: the task has ", lease->tiles.size(),
                                                   " tiles, the result ", tiles.size()));
  }
  // Decoded before the engine sees it: the one per-event pass of the coordinator's hot path,
  // outside every lock, and what keeps a hostile result from reaching the tile.
  std::vector<TileEvents> events;
  events.reserve(lease->tiles.size());
  const ResultBounds bounds{.batch_samples = lease->sample_end - lease->sample_begin,
                            .z_min = plan->z_clip_near,
                            .keying = KeyingOf(plan->header),
                            .sample_begin = lease->sample_begin};
  for (size_t i = 0; i < lease->tiles.size(); ++i) {
    absl::StatusOr<TileEvents> decoded =
        TileEventsFromProto(tiles[static_cast<int>(i)], plan->tile(lease->tiles[i]), bounds);
    if (!decoded.ok()) return decoded.status();
    events.push_back(*std::move(decoded));
  }
  const bool accepted = engine_.Report(worker_id, lease_id, std::move(events));
  if (accepted) task_seconds_.Observe(seconds);
  if (!accepted) {
    spdlog::debug("job {} tile group {}: dropped a late or duplicate result from {}", lease->job_id,
                  lease->group_index, worker_id);
  }
  return accepted;
}

void Coordinator::ReportFailure(const std::string& worker_id, uint64_t lease_id,
                                const absl::Status& failure, bool handed_back, bool incompatible) {
  const std::string reason(failure.message());
  if (incompatible) {
    const std::optional<TaskLease> lease = engine_.FindLease(lease_id);
    if (engine_.ReportIncompatible(worker_id, lease_id)) {
      spdlog::warn(
          "job {}: worker {} plans it differently ({}); it gets no more of this job's tasks "
          "(not a failure: the job waits for a worker of this coordinator's build)",
          lease ? lease->job_id : "?", worker_id, reason);
    }
    return;
  }
  spdlog::warn("lease {}: worker {} {}: {}", lease_id, worker_id,
               handed_back ? "handed the task back" : "failed", reason);
  engine_.ReportFailure(worker_id, lease_id, failure, handed_back);
}

void Coordinator::SignOff(const std::string& worker_id) {
  engine_.SignOff(worker_id);
  spdlog::info("worker {}: signed off", worker_id);
}

absl::StatusOr<std::shared_ptr<const std::string>> Coordinator::RefinedPixelsBlob(
    const std::string& job_id, const std::string& light_name) {
  const std::shared_ptr<StoredJob> job = Active(job_id);
  if (!job || job->ended()) {
    return absl::FailedPreconditionError(absl::StrCat("job ", job_id, " is not running"));
  }
  absl::StatusOr<int> light = FindJobLight(job->lights(), light_name, job_id);
  if (!light.ok()) return light.status();
  absl::StatusOr<StoredJob::LevelInfo> level = job->Level(*light);
  if (!level.ok()) return level.status();
  return level->refined_pixels;
}

absl::StatusOr<pdsm::v1::GetJobSceneResponse> Coordinator::JobScene(const std::string& job_id) {
  const std::shared_ptr<StoredJob> job = Active(job_id);
  if (!job || job->ended()) {
    return absl::FailedPreconditionError(absl::StrCat("job ", job_id, " is not running"));
  }
  pdsm::v1::GetJobSceneResponse response;
  *response.mutable_scene() = job->scene();
  response.set_plan_fingerprint(job->fingerprint());
  return response;
}

}  // namespace pdsm
