#include "worker/adaptive_bake.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <set>
#include <thread>
#include <tuple>
#include <vector>

#include "worker/tile_output.h"
#include "core/bake/adaptive_sampling.h"
#include "core/pipeline/tile_assembly.h"
#include "worker/bake_task.h"

namespace pdsm {
namespace {

// One tile's progress through its stages.
struct TileState {
  int stage = 0;
  int samples = 0;                             // end of the stage's last range
  std::vector<SampleRange> ranges;             // the current stage's ranges
  std::vector<std::vector<TileEvents>> parts;  // per range, the batches returned so far
  int tasks_left = 0;                          // batches of the current stage not yet returned
  std::vector<TileEvents> before;              // merged events of all earlier ranges
};

// A queued batch; ordered by tile first so that few tiles are in flight at once.
struct QueuedTask {
  int tile, range, begin, end;
  auto operator<=>(const QueuedTask&) const = default;
};

class AdaptiveBake {
 public:
  AdaptiveBake(const BakePlan& plan, const LocalBakeOptions& options, PdsmWriter* writer)
      : plan_(plan),
        options_(options),
        min_samples_(std::max(1, plan.header.adaptive_min_samples)),
        max_samples_(plan.header.samples),
        tiles_(plan.tiles.size()),
        output_(plan, !options.preview_path.empty(), writer) {
    std::lock_guard<std::mutex> lock(mu_);
    for (size_t t = 0; t < tiles_.size(); ++t) StartStage(static_cast<int>(t), 0);
  }

  absl::StatusOr<BakeSummary> Run(int threads) {
    start_ = std::chrono::steady_clock::now();
    std::vector<std::thread> pool;
    for (int t = 0; t < threads; ++t) pool.emplace_back([this] { WorkerLoop(); });
    for (std::thread& thread : pool) thread.join();
    if (!first_error_.ok()) return first_error_;
    summary_.tiles = static_cast<int>(plan_.tiles.size());
    summary_.tasks = tasks_done_;
    summary_.seconds = Elapsed();
    return summary_;
  }

  const PreviewImage& preview() const { return output_.preview(); }

 private:
  double Elapsed() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }

  // REQUIRES: mu_ held. Queues the batches of the tile's stage.
  void StartStage(int tile, int stage) {
    TileState& s = tiles_[tile];
    s.stage = stage;
    s.ranges = AdaptiveStageRanges(stage, min_samples_, max_samples_);
    s.parts.assign(s.ranges.size(), {});
    s.tasks_left = 0;
    for (size_t r = 0; r < s.ranges.size(); ++r) {
      const int size = s.ranges[r].end - s.ranges[r].begin;
      const int batch = options_.samples_per_task > 0 ? options_.samples_per_task : size;
      for (int b = s.ranges[r].begin; b < s.ranges[r].end; b += batch) {
        queue_.insert({tile, static_cast<int>(r), b, std::min(s.ranges[r].end, b + batch)});
        ++s.tasks_left;
      }
    }
    s.samples = s.ranges.back().end;
    tasks_total_ += s.tasks_left;
  }

  void Fail(const absl::Status& status) {
    std::lock_guard<std::mutex> lock(mu_);
    if (first_error_.ok()) first_error_ = status;
    failed_ = true;
    wake_.notify_all();
  }

  // The next batch, waiting while other threads may still queue one; false when all is done.
  bool NextTask(QueuedTask* task) {
    std::unique_lock<std::mutex> lock(mu_);
    wake_.wait(lock, [&] { return failed_ || !queue_.empty() || in_flight_ == 0; });
    if (failed_ || queue_.empty()) return false;
    *task = *queue_.begin();
    queue_.erase(queue_.begin());
    ++in_flight_;
    return true;
  }

  void WorkerLoop() {
    absl::StatusOr<std::unique_ptr<TaskRunner>> runner = TaskRunner::Create(plan_);
    if (!runner.ok()) return Fail(runner.status());
    TaskStats stats;
    AssemblyStats assembly;
    QueuedTask task;
    while (NextTask(&task)) {
      absl::Status s = RunTask(**runner, task, &stats, &assembly);
      {
        std::lock_guard<std::mutex> lock(mu_);
        --in_flight_;
        wake_.notify_all();
      }
      if (!s.ok()) return Fail(s);
    }
    std::lock_guard<std::mutex> lock(mu_);
    summary_.tasks_stats.Add(stats);
    summary_.assembly.Add(assembly);
  }

  absl::Status RunTask(TaskRunner& runner, const QueuedTask& task, TaskStats* stats,
                       AssemblyStats* assembly) {
    absl::StatusOr<TileEvents> events = runner.Run({task.tile, task.begin, task.end}, stats);
    if (!events.ok()) return events.status();
    TileState& s = tiles_[task.tile];
    std::vector<std::vector<TileEvents>> stage_parts;
    {
      std::lock_guard<std::mutex> lock(mu_);
      s.parts[task.range].push_back(*std::move(events));
      if (--s.tasks_left == 0) stage_parts.swap(s.parts);
    }
    ReportProgress();
    // The thread that returns a stage's last batch judges the tile; nobody else touches it.
    if (stage_parts.empty()) return absl::OkStatus();
    return FinishStage(runner, task.tile, stage_parts, assembly);
  }

  absl::Status FinishStage(TaskRunner& runner, int tile,
                           const std::vector<std::vector<TileEvents>>& stage_parts,
                           AssemblyStats* assembly) {
    TileState& s = tiles_[tile];
    // Merge each range's batches: exact integer sums, independent of how it was split.
    std::vector<TileEvents> ranges;
    for (const std::vector<TileEvents>& parts : stage_parts) {
      ranges.push_back(MergeTileEvents(parts));
    }
    if (!JudgeAdaptiveStage(plan_.header, s.ranges, std::move(ranges), &s.before)) {
      std::lock_guard<std::mutex> lock(mu_);
      StartStage(tile, s.stage + 1);
      wake_.notify_all();
      return absl::OkStatus();
    }
    std::vector<TileEvents> all = std::move(s.before);
    s.before.clear();
    return WriteTile(runner, all, s.samples, assembly);
  }

  absl::Status WriteTile(TaskRunner& runner, const std::vector<TileEvents>& parts, int samples,
                         AssemblyStats* assembly) {
    absl::StatusOr<bool> all_lit = output_.Write(runner, parts, samples, assembly);
    if (!all_lit.ok()) return all_lit.status();
    std::lock_guard<std::mutex> lock(mu_);
    if (*all_lit) ++summary_.tiles_all_lit;
    summary_.tile_samples_total += samples;
    return absl::OkStatus();
  }

  void ReportProgress() {
    int64_t done, total;
    {
      std::lock_guard<std::mutex> lock(mu_);
      done = ++tasks_done_;
      total = tasks_total_;
    }
    if (!options_.on_progress) return;
    std::lock_guard<std::mutex> lock(progress_mu_);
    options_.on_progress(BakeProgress{done, total, Elapsed()});
  }

  const BakePlan& plan_;
  const LocalBakeOptions& options_;
  const int min_samples_, max_samples_;
  std::chrono::steady_clock::time_point start_;

  std::mutex mu_;  // guards the members below up to progress_mu_, and TileState's queue fields
  std::condition_variable wake_;
  std::vector<TileState> tiles_;
  std::set<QueuedTask> queue_;
  int in_flight_ = 0;
  int64_t tasks_done_ = 0;
  int64_t tasks_total_ = 0;  // grows as stages are queued
  bool failed_ = false;
  absl::Status first_error_;
  BakeSummary summary_;

  std::mutex progress_mu_;
  TileOutput output_;
};

}  // namespace

absl::StatusOr<BakeSummary> RunAdaptiveTiles(const BakePlan& plan, const LocalBakeOptions& options,
                                             int threads, PdsmWriter* writer) {
  AdaptiveBake bake(plan, options, writer);
  absl::StatusOr<BakeSummary> summary = bake.Run(threads);
  if (!summary.ok()) return summary;
  if (!options.preview_path.empty()) {
    if (absl::Status s = bake.preview().Write(options.preview_path); !s.ok()) return s;
  }
  return summary;
}

}  // namespace pdsm
