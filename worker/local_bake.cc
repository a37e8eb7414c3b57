#include "worker/local_bake.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <filesystem>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "absl/strings/str_cat.h"
#include "worker/adaptive_bake.h"
#include "worker/tile_output.h"
#include "core/bake/bake_plan.h"
#include "core/bake/tile_reach.h"
#include "core/pdsm/pdsm_file.h"

namespace pdsm {
namespace {

// Tasks are ordered tile by tile, so only the tiles that threads are working on hold partial
// results: peak memory is bounded by the tiles in flight, not by the PDSM's size. A tile no
// caster can reach gets one task with no sample: it is written all lit without any shadow map.
std::vector<BakeTask> MakeTasks(const BakePlan& plan, int samples_per_task) {
  const int total = static_cast<int>(plan.samples.size());
  const int batch = samples_per_task > 0 ? samples_per_task : total;
  std::vector<BakeTask> tasks;
  for (const TileRect& tile : plan.tiles) {
    if (!TileHasCasters(plan, tile)) {
      tasks.push_back(BakeTask{tile.index, 0, 0});
      continue;
    }
    for (int begin = 0; begin < total; begin += batch) {
      tasks.push_back(BakeTask{tile.index, begin, std::min(total, begin + batch)});
    }
  }
  return tasks;
}

class LocalBake {
 public:
  LocalBake(const BakePlan& plan, const LocalBakeOptions& options, PdsmWriter* writer)
      : plan_(plan),
        options_(options),
        tasks_(MakeTasks(plan, options.samples_per_task)),
        tile_parts_(plan.tiles.size()),
        tile_parts_left_(plan.tiles.size()),
        output_(plan, !options.preview_path.empty(), writer) {
    for (const BakeTask& task : tasks_) ++tile_parts_left_[task.tile_index];
  }

  absl::StatusOr<BakeSummary> Run(int threads) {
    start_ = std::chrono::steady_clock::now();
    std::vector<std::thread> pool;
    for (int t = 0; t < threads; ++t) pool.emplace_back([this] { WorkerLoop(); });
    for (std::thread& thread : pool) thread.join();
    if (!first_error_.ok()) return first_error_;
    summary_.tiles = static_cast<int>(plan_.tiles.size());
    summary_.tasks = static_cast<int64_t>(tasks_.size());
    summary_.seconds = Elapsed();
    return summary_;
  }

  const PreviewImage& preview() const { return output_.preview(); }
  size_t task_count() const { return tasks_.size(); }

 private:
  double Elapsed() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }

  void Fail(const absl::Status& status) {
    std::lock_guard<std::mutex> lock(mu_);
    if (first_error_.ok()) first_error_ = status;
    failed_ = true;
  }

  void WorkerLoop() {
    absl::StatusOr<std::unique_ptr<TaskRunner>> runner = TaskRunner::Create(plan_);
    if (!runner.ok()) return Fail(runner.status());
    TaskStats stats;
    AssemblyStats assembly;
    while (!failed_) {
      const size_t index = next_task_.fetch_add(1);
      if (index >= tasks_.size()) break;
      if (absl::Status s = RunTask(**runner, tasks_[index], &stats, &assembly); !s.ok()) {
        return Fail(s);
      }
    }
    std::lock_guard<std::mutex> lock(mu_);
    summary_.tasks_stats.Add(stats);
    summary_.assembly.Add(assembly);
  }

  absl::Status RunTask(TaskRunner& runner, const BakeTask& task, TaskStats* stats,
                       AssemblyStats* assembly) {
    absl::StatusOr<TileEvents> events = runner.Run(task, stats);
    if (events.ok() && task.sample_begin == task.sample_end) ++stats->tiles_skipped;
    if (!events.ok()) return events.status();
    std::vector<TileEvents> parts;
    {
      std::lock_guard<std::mutex> lock(mu_);
      tile_parts_[task.tile_index].push_back(*std::move(events));
      if (--tile_parts_left_[task.tile_index] == 0) parts.swap(tile_parts_[task.tile_index]);
    }
    if (!parts.empty()) {
      if (absl::Status s = FinishTile(runner, parts, assembly); !s.ok()) return s;
    }
    ReportProgress();
    return absl::OkStatus();
  }

  absl::Status FinishTile(TaskRunner& runner, const std::vector<TileEvents>& parts,
                          AssemblyStats* assembly) {
    absl::StatusOr<bool> all_lit = output_.Write(runner, parts, /*tile_samples=*/0, assembly);
    if (!all_lit.ok()) return all_lit.status();
    if (*all_lit) {
      std::lock_guard<std::mutex> lock(mu_);
      ++summary_.tiles_all_lit;
    }
    return absl::OkStatus();
  }

  void ReportProgress() {
    const int64_t done = ++tasks_done_;
    if (!options_.on_progress) return;
    std::lock_guard<std::mutex> lock(progress_mu_);
    options_.on_progress(
        BakeProgress{done, static_cast<int64_t>(tasks_.size()), Elapsed()});
  }

  const BakePlan& plan_;
  const LocalBakeOptions& options_;
  const std::vector<BakeTask> tasks_;
  std::chrono::steady_clock::time_point start_;
  std::atomic<size_t> next_task_{0};
  std::atomic<int64_t> tasks_done_{0};
  std::atomic<bool> failed_{false};

  std::mutex mu_;  // guards the members below up to progress_mu_
  std::vector<std::vector<TileEvents>> tile_parts_;
  std::vector<int> tile_parts_left_;
  absl::Status first_error_;
  BakeSummary summary_;

  std::mutex progress_mu_;
  TileOutput output_;
};

}  // namespace

absl::StatusOr<BakeSummary> RunLocalBake(const Scene& scene, const LocalBakeOptions& options) {
  absl::StatusOr<BakePlan> plan = PlanBake(scene);
  if (!plan.ok()) return plan.status();
  absl::StatusOr<std::unique_ptr<PdsmWriter>> writer =
      PdsmWriter::Create(options.output_path, plan->header);
  if (!writer.ok()) return writer.status();

  const int cores = options.threads > 0
                        ? options.threads
                        : static_cast<int>(std::thread::hardware_concurrency());
  absl::StatusOr<BakeSummary> summary;
  if (plan->header.adaptive()) {
    summary = RunAdaptiveTiles(*plan, options, std::max(1, cores), writer->get());
    if (!summary.ok()) return summary.status();
  } else {
    LocalBake bake(*plan, options, writer->get());
    const int threads =
        std::clamp(cores, 1, static_cast<int>(std::max<size_t>(1, bake.task_count())));
    summary = bake.Run(threads);
    if (!summary.ok()) return summary.status();
    summary->tile_samples_total = int64_t{plan->header.samples} * summary->tiles;
    if (!options.preview_path.empty()) {
      if (absl::Status s = bake.preview().Write(options.preview_path); !s.ok()) return s;
    }
  }
  if (absl::Status s = (*writer)->Finish(); !s.ok()) return s;
  std::error_code ec;
  summary->file_bytes = std::filesystem::file_size(options.output_path, ec);
  return summary;
}

}  // namespace pdsm
