#include "worker/local_bake.h"

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/synchronization/mutex.h"
#include "core/bake/bake_plan.h"
#include "core/pdsm/pdsm_file.h"
#include "core/pipeline/bake_engine.h"
#include "core/pipeline/refinement_pass.h"
#include "core/util/malloc_arenas.h"
#include "core/util/work_queue.h"
#include "gl/platform/osmesa_context.h"
#include "worker/local_output.h"

namespace pdsm {
namespace {

constexpr char kJobId[] = "local";
// In one process a thread never vanishes with its lease: leases last as long as the bake.
constexpr int64_t kLocalLeaseMs = std::numeric_limits<int64_t>::max() / 4;
// How long an idle thread waits for work before looking again whether the bake is over.
constexpr absl::Duration kIdleWait = absl::Seconds(1);

// One thread of one light's bake: its task runner (borrowed from the bake, which keeps it for
// the next light), its statistics.
class LocalWorker {
 public:
  // `runner` is the bake's slot for this thread's runner: filled at Start if empty, and must
  // outlive the worker.
  LocalWorker(int index, const BakePlan& plan, GroupCache* groups, BakeEngine* engine,
              LocalOutput* output, std::unique_ptr<TaskRunner>* runner)
      : id_(absl::StrCat("local-", index)),
        plan_(plan),
        groups_(groups),
        engine_(engine),
        output_(output),
        runner_(runner) {}

  // Sets the runner on this light's plan (making it for the first light) and renders the
  // preview's receiver depths of every `stride`-th tile from `first`.
  absl::Status Start(int first, int stride) {
    if (*runner_ == nullptr) {
      absl::StatusOr<std::unique_ptr<TaskRunner>> runner = TaskRunner::Create();
      if (!runner.ok()) return runner.status();
      *runner_ = *std::move(runner);
    }
    (*runner_)->SetPlan(plan_, groups_);
    if (!output_->has_preview()) return absl::OkStatus();
    for (int t = first; t < plan_.tile_count(); t += stride) {
      absl::StatusOr<std::vector<float>> depth = (*runner_)->ReceiverDepth(plan_.tile(t));
      if (!depth.ok()) return depth.status();
      output_->SetReceiverDepth(t, *depth);
    }
    return absl::OkStatus();
  }

  // Leases, runs and reports tasks until the bake has ended.
  void RunTasks(const std::function<void()>& after_task) {
    while (!output_->ended()) {
      const std::optional<TaskLease> lease = engine_->Lease(id_, kIdleWait);
      if (!lease) continue;
      absl::StatusOr<std::vector<TileEvents>> events = (*runner_)->Run(
          BakeTask{lease->group_index, lease->tiles, lease->sample_begin, lease->sample_end},
          &stats_, [this] { return output_->ended(); });
      if (events.ok()) {
        engine_->Report(id_, lease->lease_id, *std::move(events));
      } else {
        engine_->ReportFailure(id_, lease->lease_id, events.status(),
                               /*handed_back=*/absl::IsCancelled(events.status()));
      }
      after_task();
    }
  }

  // Lets the next light's bake use the runner on another thread. Call on this worker's
  // thread, last.
  void LeaveThread() {
    if (*runner_ != nullptr) (*runner_)->LeaveThread();
  }

  const TaskStats& stats() const { return stats_; }

 private:
  const std::string id_;
  const BakePlan& plan_;
  GroupCache* const groups_;
  BakeEngine* const engine_;
  LocalOutput* const output_;
  std::unique_ptr<TaskRunner>* const runner_;
  TaskStats stats_;
};

// Light samples per task when the caller sets none: a group's samples cut so that every
// thread has a batch of it (a small map is one group), and at most kMaxLocalBatch, which bounds
// a task's events whatever the sample count.
constexpr int kMaxLocalBatch = 32;
int LocalBatch(const BakePlan& plan, int threads, const LocalBakeOptions& options) {
  if (options.samples_per_task > 0) return options.samples_per_task;
  const int samples = std::max(1, plan.header.samples);
  return std::clamp((samples + 2 * threads - 1) / (2 * threads), 1, kMaxLocalBatch);
}

// Threads worth starting: more than tasks would only cost contexts.
int ThreadCount(const BakePlan& plan, const LocalBakeOptions& options) {
  const int64_t wanted = options.threads > 0 ? options.threads : CoreCount();
  const int64_t batch = LocalBatch(plan, static_cast<int>(std::max<int64_t>(1, wanted)), options);
  const int64_t batches = (std::max(1, plan.header.samples) + batch - 1) / batch;
  const int64_t tasks = std::max<int64_t>(1, static_cast<int64_t>(plan.group_count()) * batches);
  return static_cast<int>(std::clamp<int64_t>(wanted, 1, tasks));
}

// Tiles in the largest group.
int LargestGroup(const BakePlan& plan) {
  size_t most = 1;
  for (int g = 0; g < plan.group_count(); ++g) most = std::max(most, plan.group(g).tiles.size());
  return static_cast<int>(most);
}

// Waits until all `count` threads have called Arrive; the last to arrive runs `go` first
// (the job is added only once the preview's depths are all rendered: a tile no caster reaches
// is stored, and shaded, as soon as the job is).
class StartLine {
 public:
  StartLine(int count, std::function<void()> go) : waiting_(count), go_(std::move(go)) {}
  void Arrive() {
    absl::MutexLock lock(&mu_);
    if (--waiting_ == 0) {
      mu_.Unlock();
      go_();
      mu_.Lock();
      gone_ = true;
    }
    mu_.Await(absl::Condition(&gone_));
  }

 private:
  absl::Mutex mu_;
  int waiting_ ABSL_GUARDED_BY(mu_);
  bool gone_ ABSL_GUARDED_BY(mu_) = false;
  const std::function<void()> go_;
};

// What one engine job run on the bake's threads did.
struct PlanRun {
  JobProgress progress;
  TaskStats tasks;  // summed over the threads
};

// Runs `plan`'s bake as one engine job on the bake's threads into `output`. `on_progress` gets
// its progress, seconds counted from `start`. `runners` holds the bake's task runners, one per
// thread, made here as needed and kept for the next plan: a runner's GL context and shaders
// cost ~20 ms to make, as much as the whole bake of a small light.
absl::StatusOr<PlanRun> RunPlan(std::shared_ptr<const BakePlan> plan,
                                const std::shared_ptr<LocalOutput>& output,
                                const LocalBakeOptions& options,
                                const std::function<void(const BakeProgress&)>& on_progress,
                                std::chrono::steady_clock::time_point start,
                                std::vector<std::unique_ptr<TaskRunner>>* runners) {
  const auto elapsed = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  const int threads = ThreadCount(*plan, options);
  // One GL context per thread: llvmpipe's own helper threads per context would only
  // oversubscribe the cores and cost ~27 MiB each (docs/performance.md, "GL memory").
  gl::ShareCoresBetweenContexts(threads);
  LimitMallocArenas(threads);  // core/util/malloc_arenas.h: memory flat in the samples
  EngineOptions engine_options;
  engine_options.scheduler.lease_ms = kLocalLeaseMs;
  // Enough open groups that no thread waits while another judges a stage.
  engine_options.scheduler.max_open_tiles = (threads + 1) * LargestGroup(*plan);
  engine_options.executor = [](std::function<void()> work) { work(); };
  engine_options.task_failure_ends_job = true;
  engine_options.spill_dir = ParentDir(options.output_path);
  engine_options.event_memory_budget_bytes = options.event_memory_budget_bytes;
  engine_options.fs = options.fs;
  BakeEngine engine(std::move(engine_options));
  EngineJob job;
  job.job_id = kJobId;
  job.plan = plan;
  job.samples_per_task = LocalBatch(*plan, threads, options);
  job.output = output;

  absl::Mutex progress_mu;
  const auto report_progress = [&] {
    if (!on_progress) return;
    const std::optional<JobProgress> p = engine.Progress(kJobId);
    if (!p) return;
    absl::MutexLock lock(&progress_mu);
    on_progress(BakeProgress{p->tasks_done, p->tasks_total, elapsed()});
  };
  GroupCache groups(*plan);  // each group prepared once, whichever thread needs it first
  if (runners->size() < static_cast<size_t>(threads)) runners->resize(threads);
  std::vector<std::unique_ptr<LocalWorker>> workers;
  for (int t = 0; t < threads; ++t) {
    workers.push_back(
        std::make_unique<LocalWorker>(t, *plan, &groups, &engine, output.get(), &(*runners)[t]));
  }
  absl::Mutex start_mu;
  absl::Status started;  // the first runner that could not start, else AddJob's
  StartLine start_line(threads, [&] {
    absl::MutexLock lock(&start_mu);
    if (started.ok()) started = engine.AddJob(std::move(job));
  });
  WorkQueue queue(threads);
  for (int t = 0; t < threads; ++t) {
    queue.Post([&, t] {
      if (absl::Status s = workers[t]->Start(t, threads); !s.ok()) {
        absl::MutexLock lock(&start_mu);
        if (started.ok()) started = s;
      }
      start_line.Arrive();
      bool go;
      {
        absl::MutexLock lock(&start_mu);
        go = started.ok();
      }
      if (go) workers[t]->RunTasks(report_progress);
      workers[t]->LeaveThread();
    });
  }
  queue.Wait();
  if (!started.ok()) return started;
  if (!output->ended()) return absl::InternalError("the local bake stopped before its end");
  if (absl::Status s = output->status(); !s.ok()) return s;
  PlanRun run;
  run.progress = output->progress();
  for (const auto& w : workers) run.tasks.Add(w->stats());
  run.tasks.tiles_skipped += run.progress.tiles_without_task;
  return run;
}

// Adaptive resolution (docs/algorithms.md section 10) once the base of light `light` (nullopt:
// the scene's one light) is baked into `base_output`: chooses the pixels to refine, bakes the
// refinement level on the bake's threads, and puts the spliced tiles in place of the base's.
absl::StatusOr<RefinementSummary> RefineLight(
    const SceneIndex& index, std::optional<size_t> light, const BakePlan& base,
    LocalOutput* base_output, const LocalBakeOptions& options,
    const std::function<void(const BakeProgress&)>& on_progress, int64_t tasks_before,
    std::chrono::steady_clock::time_point start,
    std::vector<std::unique_ptr<TaskRunner>>* runners) {
  const auto since = [](std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
  };
  RefinementSummary summary;
  summary.lights = 1;
  const int threads = options.threads > 0 ? options.threads : CoreCount();
  EncodedTileStore& tiles = base_output->tiles();
  const BaseTileSource base_tile = [&](int t) {
    const TileRect rect = base.tile(t);
    return tiles.Get(rect.x0, rect.y0);
  };
  auto step = std::chrono::steady_clock::now();
  absl::StatusOr<std::shared_ptr<const RefinedPixels>> refined =
      SelectRefinedPixels(base, base_tile, threads);
  if (!refined.ok()) return refined.status();
  summary.select_seconds = since(step);
  if ((*refined)->empty()) return summary;
  summary.factor = (*refined)->factor();
  summary.pixels = (*refined)->count();

  absl::StatusOr<BakePlan> planned = PlanRefinementLevel(index, light, base, *refined);
  if (!planned.ok()) return planned.status();
  const auto level = std::make_shared<const BakePlan>(*std::move(planned));
  const auto level_output = std::make_shared<LocalOutput>(*level, /*writer=*/nullptr, "",
                                                          options.output_path, options.fs);
  std::function<void(const BakeProgress&)> level_progress;
  if (on_progress) {
    level_progress = [&](const BakeProgress& p) {
      on_progress(
          BakeProgress{tasks_before + p.tasks_done, tasks_before + p.tasks_total, p.seconds});
    };
  }
  absl::StatusOr<PlanRun> run =
      RunPlan(level, level_output, options, level_progress, start, runners);
  if (!run.ok()) return run.status();
  summary.tasks = run->progress.tasks_done;
  summary.tasks_stats = run->tasks;
  summary.assembly = run->progress.assembly;

  step = std::chrono::steady_clock::now();
  EncodedTileStore& level_tiles = level_output->tiles();
  const LevelTileSource level_tile = [&](int t) -> absl::StatusOr<std::optional<PdsmTile>> {
    const TileRect rect = level->tile(t);
    absl::StatusOr<PdsmTile> tile = level_tiles.Get(rect.x0, rect.y0);
    if (!tile.ok()) return tile.status();
    return std::optional<PdsmTile>(*std::move(tile));
  };
  if (absl::Status s = SpliceRefinedTiles(
          base, *level, base_tile, level_tile, [&](const PdsmTile& t) { return tiles.Replace(t); },
          threads);
      !s.ok()) {
    return s;
  }
  summary.splice_seconds = since(step);
  return summary;
}

// Bakes one light's plan into `writer` (a file, or one part of a multipart file), with the
// light-view preview at `preview_path` ("": none), and refines it when its plan asks for it.
// `on_progress` gets this light's progress; `light` names the light of `index`'s scene (nullopt:
// its one light), for the refinement levels' plans.
absl::StatusOr<BakeSummary> BakePlanned(const SceneIndex& index, std::optional<size_t> light,
                                        std::shared_ptr<const BakePlan> plan, PdsmWriter* writer,
                                        const std::string& preview_path,
                                        const LocalBakeOptions& options,
                                        const std::function<void(const BakeProgress&)>& on_progress,
                                        std::vector<std::unique_ptr<TaskRunner>>* runners) {
  const auto start = std::chrono::steady_clock::now();
  const bool refine = plan->header.max_refinement > 1;
  // A refined light's tiles are written once its levels are spliced in.
  auto output = std::make_shared<LocalOutput>(*plan, refine ? nullptr : writer, preview_path,
                                              options.output_path, options.fs);
  absl::StatusOr<PlanRun> run = RunPlan(plan, output, options, on_progress, start, runners);
  if (!run.ok()) return run.status();
  BakeSummary summary;
  if (refine) {
    absl::StatusOr<RefinementSummary> refinement =
        RefineLight(index, light, *plan, output.get(), options, on_progress,
                    run->progress.tasks_done, start, runners);
    if (!refinement.ok()) return refinement.status();
    summary.refinement = *std::move(refinement);
    if (absl::Status s = output->tiles().WriteTo(writer); !s.ok()) return s;
    if (absl::Status s = writer->Finish(); !s.ok()) return s;
  }

  const JobProgress& progress = run->progress;
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  summary.tiles = progress.tiles_total;
  summary.tiles_all_lit = progress.tiles_all_lit;
  summary.groups = plan->group_count();
  summary.casters_left_out = static_cast<int64_t>(plan->casters_left_out);
  summary.casters = static_cast<int64_t>(plan->casters.TriangleCount()) + summary.casters_left_out;
  summary.tasks = progress.tasks_done + summary.refinement.tasks;
  summary.tile_samples_total = progress.tile_samples_total;
  summary.assembly = progress.assembly;
  summary.spilled_bytes = progress.spilled_bytes;
  summary.tasks_stats = run->tasks;
  summary.light_name = plan->header.light_name;
  summary.width = plan->header.geometry.width;
  summary.height = plan->header.geometry.height;
  summary.samples = plan->header.samples;
  return summary;
}

// The sums over lights of `light` into `total`.
void AddLight(const BakeSummary& light, BakeSummary* total) {
  total->tiles += light.tiles;
  total->tiles_all_lit += light.tiles_all_lit;
  total->groups += light.groups;
  total->casters += light.casters;
  total->casters_left_out += light.casters_left_out;
  total->tasks += light.tasks;
  total->tile_samples_total += light.tile_samples_total;
  total->tasks_stats.Add(light.tasks_stats);
  total->assembly.Add(light.assembly);
  total->spilled_bytes += light.spilled_bytes;
  total->refinement.Add(light.refinement);
}

}  // namespace

void RefinementSummary::Add(const RefinementSummary& o) {
  lights += o.lights;
  factor = std::max(factor, o.factor);
  pixels += o.pixels;
  tasks += o.tasks;
  tasks_stats.Add(o.tasks_stats);
  assembly.Add(o.assembly);
  select_seconds += o.select_seconds;
  splice_seconds += o.splice_seconds;
}

std::string LightPreviewPath(const std::string& preview_path, const std::string& light_name) {
  if (preview_path.empty()) return "";
  std::filesystem::path path(preview_path);
  const std::string extension = path.extension().string();
  return path.replace_extension(absl::StrCat(".", light_name, extension)).string();
}

absl::StatusOr<BakeSummary> RunLocalBake(const Scene& scene, const LocalBakeOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const auto elapsed = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  BakeSummary total;
  std::vector<std::unique_ptr<TaskRunner>> runners;  // one per thread, kept across lights
  // One index of the world's triangles serves every light's plan (and refinement level).
  absl::StatusOr<std::shared_ptr<const SceneIndex>> index = SceneIndex::Build(scene);
  if (!index.ok()) return index.status();
  if (scene.LightCount() == 1) {
    absl::StatusOr<BakePlan> planned = PlanBake(**index);
    if (!planned.ok()) return planned.status();
    if (!options.preview_path.empty()) AddLightSpaceReceivers(scene, &*planned);
    const auto plan = std::make_shared<const BakePlan>(*std::move(planned));
    absl::StatusOr<std::unique_ptr<PdsmWriter>> writer =
        PdsmWriter::Create(options.output_path, plan->header, options.fs);
    if (!writer.ok()) return writer.status();
    absl::StatusOr<BakeSummary> light =
        BakePlanned(**index, std::nullopt, plan, writer->get(), options.preview_path, options,
                    options.on_progress, &runners);
    if (!light.ok()) return light.status();
    total = *std::move(light);
  } else {
    // One light after another, each into its part; progress counts every light's tasks so far.
    int max_width = 1, max_height = 1;
    for (size_t i = 0; i < scene.LightCount(); ++i) {
      const BakeSettings bake = LightOf(scene, i).bake;
      max_width = std::max(max_width, bake.width);
      max_height = std::max(max_height, bake.height);
    }
    absl::StatusOr<std::unique_ptr<PdsmLightsWriter>> writer =
        PdsmLightsWriter::Create(options.output_path, static_cast<int>(scene.LightCount()),
                                 max_width, max_height, options.fs);
    if (!writer.ok()) return writer.status();
    int64_t tasks_before = 0;
    for (size_t i = 0; i < scene.LightCount(); ++i) {
      absl::StatusOr<BakePlan> planned = PlanBake(**index, i);
      if (!planned.ok()) return planned.status();
      if (!options.preview_path.empty()) AddLightSpaceReceivers(scene, &*planned);
      const auto plan = std::make_shared<const BakePlan>(*std::move(planned));
      absl::StatusOr<PdsmWriter*> part = (*writer)->BeginLight(plan->header);
      if (!part.ok()) return part.status();
      std::function<void(const BakeProgress&)> on_progress;
      if (options.on_progress) {
        on_progress = [&](const BakeProgress& p) {
          options.on_progress(
              BakeProgress{tasks_before + p.tasks_done, tasks_before + p.tasks_total, elapsed()});
        };
      }
      absl::StatusOr<BakeSummary> light = BakePlanned(
          **index, i, plan, *part, LightPreviewPath(options.preview_path, plan->header.light_name),
          options, on_progress, &runners);
      if (!light.ok()) return light.status();
      tasks_before += light->tasks;
      AddLight(*light, &total);
      total.lights.push_back(*std::move(light));
    }
    if (absl::Status s = (*writer)->Finish(); !s.ok()) return s;
  }
  total.seconds = elapsed();
  std::error_code ec;
  total.file_bytes = std::filesystem::file_size(options.output_path, ec);
  return total;
}

}  // namespace pdsm
