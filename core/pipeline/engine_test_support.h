// What the engine's tests share: a small plan without geometry, the events a worker would
// return for it, and an output that records what the engine asks of it.
#ifndef PDSM_CORE_PIPELINE_ENGINE_TEST_SUPPORT_H_
#define PDSM_CORE_PIPELINE_ENGINE_TEST_SUPPORT_H_

#include <map>
#include <memory>
#include <vector>

#include <gtest/gtest.h>

#include "absl/status/status.h"
#include "absl/synchronization/mutex.h"
#include "absl/synchronization/notification.h"
#include "core/pipeline/bake_engine.h"

namespace pdsm::testing {

// A plan of `tiles_x` x 1 tiles of 2x1 pixels, without geometry: the engine only reads the
// header, the tile grid and the groups (`group_size` consecutive tiles each).
inline std::shared_ptr<const BakePlan> SmallPlan(int tiles_x, int samples,
                                                 double adaptive_tolerance = 0,
                                                 int adaptive_min_samples = 0, int group_size = 1) {
  auto plan = std::make_shared<BakePlan>();
  PdsmHeader& h = plan->header;
  h.samples = samples;
  h.tile_size = 2;
  h.epsilon = 0;
  h.geometry.width = 2 * tiles_x;
  h.geometry.height = 1;
  h.geometry.z_near = 1;
  h.geometry.z_far = 10;
  h.adaptive_tolerance = adaptive_tolerance;
  h.adaptive_min_samples = adaptive_min_samples;
  plan->tiles_x = tiles_x;
  plan->tiles_y = 1;
  plan->group_side = group_size;
  return plan;
}

// The events of samples [begin, end) of tile `tile`: in pixel 0 sample k is in shadow from
// depth 2 + k % 3 to 8 (so the answer depends on every sample); pixel 1 is lit.
inline TileEvents BatchEvents(const BakePlan& plan, int tile, int begin, int end) {
  const TileRect r = plan.tile(tile);
  TileEvents out{.tile_index = tile, .x0 = r.x0, .y0 = r.y0, .width = r.width, .height = r.height};
  std::vector<Event> pixel;
  for (int k = begin; k < end; ++k) {
    pixel.push_back({static_cast<float>(2 + k % 3 + tile), +1});
    pixel.push_back({8.0f, -1});
  }
  NormalizeEvents(&pixel, EventKeying::kCounts);
  out.events = pixel;
  out.offsets = {0, pixel.size(), pixel.size()};
  return out;
}

// Records what the engine asks of an output; StoreTile can be held to race a cancel.
class RecordingOutput : public JobOutput {
 public:
  void Started() override {
    absl::MutexLock lock(&mu_);
    ++started_;
  }
  absl::Status StoreTile(const PdsmTile& tile) override {
    if (hold_store_) {
      store_entered_.Notify();
      release_store_.WaitForNotification();
    }
    absl::MutexLock lock(&mu_);
    EXPECT_EQ(ended_, 0) << "StoreTile after Ended";
    tiles_[tile.x0 / 2] = tile;
    ++uncommitted_;
    return store_error_;
  }
  absl::Status CommitTiles() override {
    absl::MutexLock lock(&mu_);
    EXPECT_EQ(ended_, 0) << "CommitTiles after Ended";
    ++commits_;
    if (commit_error_.ok()) uncommitted_ = 0;
    return commit_error_;
  }
  absl::Status WithdrawTiles(const std::vector<int>& tile_indices) override {
    absl::MutexLock lock(&mu_);
    EXPECT_EQ(finished_, 0) << "WithdrawTiles after Finish";
    for (int t : tile_indices) {
      EXPECT_TRUE(tiles_.erase(t)) << "tile " << t << " withdrawn but not stored";
      ++withdrawn_;
    }
    return absl::OkStatus();
  }
  absl::Status Finish() override {
    absl::MutexLock lock(&mu_);
    EXPECT_EQ(ended_, 0) << "Finish after Ended";
    EXPECT_EQ(uncommitted_, 0) << "Finish before every stored tile was committed";
    ++finished_;
    return absl::OkStatus();
  }
  void Ended(JobEnd end, const absl::Status& status, const JobProgress& progress) override {
    absl::MutexLock lock(&mu_);
    // A second call is a failure the tests count (ended() == 1), not a second Notify, which
    // would abort the process before any expectation is printed.
    if (++ended_ > 1) return;
    end_ = end;
    status_ = status;
    progress_ = progress;
    ended_note_.Notify();
  }

  int started() {
    absl::MutexLock lock(&mu_);
    return started_;
  }
  int finished() {
    absl::MutexLock lock(&mu_);
    return finished_;
  }
  int ended() {
    absl::MutexLock lock(&mu_);
    return ended_;
  }
  JobEnd end() {
    absl::MutexLock lock(&mu_);
    return end_;
  }
  absl::Status status() {
    absl::MutexLock lock(&mu_);
    return status_;
  }
  JobProgress progress() {
    absl::MutexLock lock(&mu_);
    return progress_;
  }
  std::map<int, PdsmTile> tiles() {
    absl::MutexLock lock(&mu_);
    return tiles_;
  }
  int withdrawn() {
    absl::MutexLock lock(&mu_);
    return withdrawn_;
  }
  int commits() {
    absl::MutexLock lock(&mu_);
    return commits_;
  }

  bool hold_store_ = false;
  absl::Notification store_entered_, release_store_, ended_note_;
  absl::Status store_error_, commit_error_;

 private:
  absl::Mutex mu_;
  int started_ = 0, finished_ = 0, ended_ = 0, withdrawn_ = 0, commits_ = 0, uncommitted_ = 0;
  JobEnd end_ = JobEnd::kFailed;
  absl::Status status_;
  JobProgress progress_;
  std::map<int, PdsmTile> tiles_;
};

// The events of a lease: one TileEvents per tile of it, in order.
inline std::vector<TileEvents> LeaseEvents(const BakePlan& plan, const TaskLease& lease) {
  std::vector<TileEvents> out;
  for (int tile : lease.tiles) {
    out.push_back(BatchEvents(plan, tile, lease.sample_begin, lease.sample_end));
  }
  return out;
}

// One tile's events as a lease result.
inline std::vector<TileEvents> One(TileEvents events) {
  std::vector<TileEvents> out;
  out.push_back(std::move(events));
  return out;
}

inline EngineOptions InlineOptions() {
  EngineOptions options;
  options.executor = [](std::function<void()> work) { work(); };
  options.scheduler.lease_ms = 1000;
  return options;
}

inline EngineJob Job(std::shared_ptr<const BakePlan> plan, std::shared_ptr<JobOutput> output,
                     int samples_per_task) {
  EngineJob job;
  job.job_id = "j";
  job.plan = std::move(plan);
  job.samples_per_task = samples_per_task;
  job.output = std::move(output);
  return job;
}

}  // namespace pdsm::testing

#endif  // PDSM_CORE_PIPELINE_ENGINE_TEST_SUPPORT_H_
