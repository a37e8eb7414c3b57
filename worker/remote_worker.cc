#include "worker/remote_worker.h"

#include <algorithm>
#include <chrono>
#include <random>
#include <thread>
#include <vector>

#include <spdlog/spdlog.h>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "core/assets/mesh_asset.h"
#include "core/bake/plan_fingerprint.h"
#include "core/bake/refined_pixels_codec.h"
#include "core/scene/scene.h"
#include "core/scene/scene_loader.h"
#include "core/util/backoff.h"
#include "core/util/malloc_arenas.h"
#include "core/util/work_queue.h"
#include "gl/platform/osmesa_context.h"
#include "worker/bake_task.h"

namespace pdsm {
namespace {

constexpr size_t kCachedJobs = 4;
// Retries of a failed lease call: from 100 ms, doubling, to 5 s (core/util/backoff.h).
constexpr auto kFirstBackoff = std::chrono::milliseconds(100);
constexpr auto kMaxBackoff = std::chrono::milliseconds(5000);

double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// Sleeps up to `duration`, waking early once `stopping()` is true.
template <typename Stopping>
void SleepUnless(std::chrono::milliseconds duration, const Stopping& stopping) {
  const auto end = std::chrono::steady_clock::now() + duration;
  while (!stopping() && std::chrono::steady_clock::now() < end) {
    std::this_thread::sleep_for(
        std::min<std::chrono::milliseconds>(duration, std::chrono::milliseconds(50)));
  }
}

// What to do about a permanent error, for the one line the worker exits with.
std::string Remedy(const absl::Status& status) {
  if (absl::IsUnimplemented(status)) {
    return "the coordinator does not speak this worker's API: run the same pdsm release on both";
  }
  // Verification outvoted this worker (docs/service.md): the token is fine, the machine is not.
  if (absl::IsPermissionDenied(status) && absl::StrContains(status.message(), "quarantined")) {
    return "do not restart it on this machine before the check the coordinator asks for";
  }
  return "check --token-file: it must hold the coordinator's worker token "
         "(its --worker-token-file)";
}

}  // namespace

bool RemoteWorker::StopIfPermanent(const absl::Status& status) {
  if (!absl::IsUnauthenticated(status) && !absl::IsPermissionDenied(status) &&
      !absl::IsUnimplemented(status)) {
    return false;
  }
  absl::MutexLock lock(&fatal_mu_);
  if (fatal_.ok()) {
    fatal_ = absl::Status(status.code(), absl::StrCat("the coordinator refused this worker (",
                                                      absl::StatusCodeToString(status.code()), ": ",
                                                      status.message(), "): ", Remedy(status)));
  }
  fatal_stop_ = true;
  return true;
}

absl::StatusOr<std::unique_ptr<RemoteWorker>> RemoteWorker::Create(
    CoordinatorClient* client, const RemoteWorkerOptions& options) {
  absl::StatusOr<std::unique_ptr<AssetStore>> assets = AssetStore::Open(options.cache_dir);
  if (!assets.ok()) return assets.status();
  return std::unique_ptr<RemoteWorker>(new RemoteWorker(client, options, *std::move(assets)));
}

RemoteWorker::~RemoteWorker() = default;

absl::Status RemoteWorker::Run(const std::atomic<bool>& stop) {
  const int threads = std::max(1, options_.threads);
  gl::ShareCoresBetweenContexts(threads);  // one context per task thread, as the local bake
  LimitMallocArenas(threads);              // core/util/malloc_arenas.h: memory flat in the samples
  WorkQueue queue(threads + 1);            // the task threads and the lease keeper
  queue.Post([&] { KeepLeases(stop); });
  for (int t = 0; t < threads; ++t) queue.Post([&] { ThreadLoop(stop); });
  queue.Wait();
  absl::MutexLock lock(&fatal_mu_);
  if (!fatal_.ok()) return fatal_;
  // Leave the active workers now rather than when the coordinator stops hearing from us; an
  // older coordinator without the call answers UNIMPLEMENTED, which changes nothing.
  if (absl::Status s = client_->SignOff(); !s.ok()) {
    spdlog::debug("sign-off: {}", std::string(s.message()));
  }
  return absl::OkStatus();
}

// ---- Job contexts ----------------------------------------------------------------------

absl::StatusOr<std::shared_ptr<const RemoteWorker::JobContext>> RemoteWorker::Context(
    const JobKey& key) {
  absl::MutexLock lock(&jobs_mu_);
  auto it = jobs_.find(key);
  if (it != jobs_.end()) return it->second;
  absl::StatusOr<std::shared_ptr<const JobContext>> context = LoadContext(key);
  if (!context.ok()) return context.status();
  if (jobs_.size() >= kCachedJobs) jobs_.erase(jobs_.begin());  // threads keep their copies
  jobs_[key] = *context;
  return context;
}

absl::StatusOr<RemoteWorker::JobWorld> RemoteWorker::JobScene(const std::string& job_id) {
  if (world_.scene && scene_job_ == job_id) return world_;
  absl::StatusOr<pdsm::v1::GetJobSceneResponse> scene = client_->JobScene(job_id);
  if (!scene.ok()) return scene.status();
  const MeshAssetResolver resolver =
      [this](const std::string& sha256,
             const std::string& context) -> absl::StatusOr<MeshFileData> {
    absl::StatusOr<std::string> blob = assets_->Get(sha256);
    if (!blob.ok()) {
      blob = client_->FetchAsset(sha256);
      if (!blob.ok()) return blob.status();
      if (absl::Status s = assets_->Put(sha256, *blob); !s.ok()) return s;
      spdlog::info("asset {}: fetched, {} bytes", sha256, blob->size());
    }
    return DecodeMeshAsset(*blob, context);
  };
  absl::StatusOr<Scene> loaded =
      SceneFromProto(scene->scene(), absl::StrCat("job ", job_id), "", resolver);
  if (!loaded.ok()) return loaded.status();
  JobWorld world;
  world.scene = std::make_shared<const Scene>(*std::move(loaded));
  absl::StatusOr<std::shared_ptr<const SceneIndex>> index = SceneIndex::Build(*world.scene);
  if (!index.ok()) return index.status();
  world.index = *std::move(index);
  // Kept for the job's other lights, and for a refined light's level: a one-light job that
  // does not refine is planned once.
  bool refines = false;
  for (size_t i = 0; i < world.scene->LightCount(); ++i) {
    refines = refines || LightOf(*world.scene, i).bake.max_refinement > 1;
  }
  if (world.scene->LightCount() > 1 || refines) {
    world_ = world;
    scene_job_ = job_id;
  }
  return world;
}

absl::StatusOr<std::shared_ptr<const RemoteWorker::JobContext>> RemoteWorker::LoadContext(
    const JobKey& key) {
  const auto& [job_id, light, level] = key;
  absl::StatusOr<JobWorld> world = JobScene(job_id);
  if (!world.ok()) return world.status();
  const Scene& scene = *world->scene;
  // The light as the coordinator planned it: the scene as it stands for its only light, else
  // the scene baking the named one.
  absl::StatusOr<BakePlan> plan;
  std::optional<size_t> which;
  if (light.empty() && scene.LightCount() == 1) {
    plan = PlanBake(*world->index);
  } else {
    const int index = light.empty() ? -1 : FindLight(scene, light);
    if (index < 0) {
      return absl::InvalidArgumentError(absl::StrCat("job ", job_id, ": the task's light \"", light,
                                                     "\" is not one of the scene's ",
                                                     scene.LightCount(), " lights"));
    }
    which = static_cast<size_t>(index);
    plan = PlanBake(*world->index, *which);
  }
  if (!plan.ok()) return plan.status();
  if (level) {
    // Its refinement level: the pixels the coordinator chose from the light's base map.
    absl::StatusOr<std::string> blob = client_->FetchRefinement(job_id, light);
    if (!blob.ok()) return blob.status();
    absl::StatusOr<std::shared_ptr<const RefinedPixels>> refined = DecodeRefinedPixels(
        *blob, *plan, absl::StrCat("job ", job_id, light.empty() ? "" : " light ", light));
    if (!refined.ok()) return refined.status();
    plan = PlanRefinementLevel(*world->index, which, *plan, *std::move(refined));
    if (!plan.ok()) return plan.status();
  }
  auto context = std::make_shared<JobContext>();
  context->plan = *std::move(plan);
  // Compared with each task's (ThreadLoop): a mismatch makes the job incompatible here.
  context->fingerprint = PlanFingerprint(context->plan) + options_.test_fingerprint_salt;
  context->groups = std::make_unique<GroupCache>(context->plan);
  spdlog::info("job {}{}{}: planned, {} tiles, {} samples", job_id,
               light.empty() ? "" : absl::StrCat(" light ", light),
               level ? absl::StrCat(" refinement level ", context->plan.refinement, "x") : "",
               context->plan.tile_count(), context->plan.samples.size());
  return std::shared_ptr<const JobContext>(std::move(context));
}

// ---- Leases ----------------------------------------------------------------------------

void RemoteWorker::KeepLeases(const std::atomic<bool>& stop) {
  while (!Stopping(stop)) {
    int64_t lease_ms;
    std::vector<std::pair<uint64_t, std::shared_ptr<RunningLease>>> current;
    {
      absl::MutexLock lock(&leases_mu_);
      lease_ms = lease_ms_;
      current.assign(leases_.begin(), leases_.end());
    }
    for (auto& [id, lease] : current) {
      if (lease->lost) continue;
      absl::StatusOr<int64_t> extended = client_->Extend(id);
      if (!extended.ok() && StopIfPermanent(extended.status())) return;
      // UNAVAILABLE: the coordinator may be restarting; keep working and try again.
      if (!extended.ok() && !absl::IsUnavailable(extended.status()) &&
          !absl::IsDeadlineExceeded(extended.status())) {
        spdlog::info("lease {}: lost ({}); dropping the task", id,
                     std::string(extended.status().message()));
        lease->lost = true;
      }
    }
    // Three extensions per lease period: one lost call still leaves a margin.
    SleepUnless(std::chrono::milliseconds(std::max<int64_t>(50, lease_ms / 3)),
                [&] { return Stopping(stop); });
  }
}

// ---- Tasks -----------------------------------------------------------------------------

void RemoteWorker::ThreadLoop(const std::atomic<bool>& stop) {
  JobKey runner_job;  // (job id, light, level) of `runner`
  std::shared_ptr<const JobContext> context;
  std::unique_ptr<TaskRunner> runner;
  std::shared_ptr<const JobContext> runner_context;  // keeps the runner's plan alive
  const auto stopping = [&] { return Stopping(stop); };
  Backoff backoff(kFirstBackoff, kMaxBackoff, std::random_device{}());
  while (!stopping()) {
    absl::StatusOr<pdsm::v1::LeaseTaskResponse> response = client_->Lease();
    if (!response.ok()) {
      if (StopIfPermanent(response.status())) return;
      const std::chrono::milliseconds wait = backoff.Next();
      spdlog::warn("lease: {} (retrying in {} ms)", std::string(response.status().message()),
                   wait.count());
      SleepUnless(wait, stopping);
      continue;
    }
    backoff.Reset();
    if (!response->has_task()) {
      SleepUnless(std::chrono::milliseconds(response->retry_after_ms()), stopping);
      continue;
    }
    const pdsm::v1::Task& task = response->task();
    const auto start = std::chrono::steady_clock::now();
    const auto fail = [&](const absl::Status& s, TaskFailure kind) {
      ++(kind == TaskFailure::kFailed       ? metrics_.tasks_failed
         : kind == TaskFailure::kHandedBack ? metrics_.tasks_handed_back
                                            : metrics_.tasks_incompatible);
      if (kind == TaskFailure::kHandedBack) {  // stopping, not a fault: no warning
        spdlog::info("job {} tile group {}: handed back to the coordinator", task.job_id(),
                     task.group_index());
      } else {
        spdlog::warn("job {} tile group {}: {}", task.job_id(), task.group_index(),
                     std::string(s.message()));
      }
      (void)client_->ReportFailure(task.lease_id(), s, kind);
    };

    auto lease = std::make_shared<RunningLease>();
    {
      absl::MutexLock lock(&leases_mu_);
      leases_[task.lease_id()] = lease;
      lease_ms_ = task.lease_ms();
    }
    const auto forget_lease = [&] {
      absl::MutexLock lock(&leases_mu_);
      leases_.erase(task.lease_id());
    };

    const JobKey task_job(task.job_id(), task.light(), task.refinement_level());
    if (runner_job != task_job) {
      runner_job = {};
      absl::StatusOr<std::shared_ptr<const JobContext>> loaded = Context(task_job);
      if (!loaded.ok()) {
        forget_lease();
        fail(loaded.status(), TaskFailure::kFailed);
        continue;
      }
      context = *loaded;
    }
    // Before a runner (an OSMesa context) is made for it: another build's job is not ours.
    if (context->fingerprint != task.plan_fingerprint()) {
      forget_lease();
      fail(absl::FailedPreconditionError(
               absl::StrCat("this worker's build plans job ", task.job_id(),
                            " differently (fingerprint ", context->fingerprint.substr(0, 12),
                            " vs the coordinator's ", task.plan_fingerprint().substr(0, 12), ")")),
           TaskFailure::kIncompatible);
      continue;
    }
    // One runner per thread for every job and light: its context and compiled shaders are
    // kept (making them costs more than a small light's whole task).
    if (runner == nullptr) {
      absl::StatusOr<std::unique_ptr<TaskRunner>> created = TaskRunner::Create();
      if (!created.ok()) {
        forget_lease();
        fail(created.status(), TaskFailure::kFailed);
        continue;
      }
      runner = *std::move(created);
    }
    if (runner_job != task_job) {
      runner->SetPlan(context->plan, context->groups.get());
      runner_context = context;
      runner_job = task_job;
    }

    // The runner checks the group and its tiles against the plan (INVALID_ARGUMENT).
    TaskStats stats;
    const BakeTask bake_task{
        task.group_index(),
        std::vector<int>(task.tile_indices().begin(), task.tile_indices().end()),
        task.sample_begin(), task.sample_end()};
    ++metrics_.tasks_running;
    absl::StatusOr<std::vector<TileEvents>> events =
        runner->Run(bake_task, &stats, [&] { return stopping() || lease->lost.load(); });
    --metrics_.tasks_running;
    forget_lease();
    if (lease->lost) {  // the coordinator has moved on; nothing to report
      ++metrics_.leases_lost;
      continue;
    }
    if (!events.ok()) {
      fail(events.status(),
           absl::IsCancelled(events.status()) ? TaskFailure::kHandedBack : TaskFailure::kFailed);
      continue;
    }
    absl::StatusOr<bool> accepted =
        client_->ReportResult(task.lease_id(), *events, SecondsSince(start));
    if (!accepted.ok() && StopIfPermanent(accepted.status())) return;
    if (accepted.ok()) {
      ++(*accepted ? metrics_.results_accepted : metrics_.results_dropped);
      metrics_.events += stats.events;
      metrics_.task_seconds.Observe(SecondsSince(start));
      metrics_.shadow_map_seconds.Observe(stats.shadow_map_seconds);
      metrics_.scan_seconds.Observe(stats.scan_seconds);
    } else {
      ++metrics_.results_undelivered;
    }
    if (!accepted.ok()) {
      spdlog::warn("job {} tile group {}: result not delivered: {}", task.job_id(),
                   task.group_index(), std::string(accepted.status().message()));
    } else {
      spdlog::debug("job {} tile group {}: samples [{}, {}) {} in {:.3f} s, {} events",
                    task.job_id(), task.group_index(), task.sample_begin(), task.sample_end(),
                    *accepted ? "accepted" : "dropped as stale", SecondsSince(start), stats.events);
    }
  }
}

}  // namespace pdsm
