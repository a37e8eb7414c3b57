// Verification by redundancy through the engine (bake_engine.h): agreeing workers bake the
// tiles one worker bakes; a worker that lies is outvoted, quarantined, and every tile it fed
// (open or already stored) is computed again, so the output is still exact.
#include <map>
#include <memory>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/pipeline/bake_engine.h"
#include "core/pipeline/engine_test_support.h"
#include "core/pipeline/unreached_tile.h"

namespace pdsm {
namespace {

using ::testing::HasSubstr;
using testing::InlineOptions;
using testing::Job;
using testing::LeaseEvents;
using testing::RecordingOutput;
using testing::SmallPlan;

// What a lying worker returns: well-formed and plausible (no count outside its batch) but
// wrong: every pixel lit. Only comparison with another worker can tell.
std::vector<TileEvents> AllLit(const BakePlan& plan, const TaskLease& lease) {
  std::vector<TileEvents> out;
  for (int tile : lease.tiles) out.push_back(NoShadowEvents(plan.tile(tile)));
  return out;
}

// The workers take turns: every one leases a task, then every one reports its task (a liar
// lies), until a round hands out nothing. Returns the tasks run.
int RunFarm(BakeEngine& engine, const BakePlan& plan, const std::vector<std::string>& workers,
            const std::set<std::string>& liars = {}) {
  int tasks = 0;
  for (int round = 0; round < 10'000; ++round) {
    std::vector<std::pair<std::string, TaskLease>> leased;
    for (const std::string& w : workers) {
      if (std::optional<TaskLease> lease = engine.Lease(w)) leased.emplace_back(w, *lease);
    }
    if (leased.empty()) return tasks;
    for (const auto& [w, lease] : leased) {
      engine.Report(w, lease.lease_id,
                    liars.contains(w) ? AllLit(plan, lease) : LeaseEvents(plan, lease));
      ++tasks;
    }
  }
  ADD_FAILURE() << "the farm never ran out of tasks";
  return tasks;
}

// The tiles of the same job baked by one worker without verification.
std::map<int, PdsmTile> Reference(std::shared_ptr<const BakePlan> plan, int samples_per_task) {
  auto output = std::make_shared<RecordingOutput>();
  BakeEngine engine(InlineOptions());
  EXPECT_TRUE(engine.AddJob(Job(plan, output, samples_per_task)).ok());
  RunFarm(engine, *plan, {"w"});
  EXPECT_EQ(output->end(), JobEnd::kSucceeded);
  return output->tiles();
}

void ExpectSameTiles(const std::map<int, PdsmTile>& got, const std::map<int, PdsmTile>& want) {
  ASSERT_EQ(got.size(), want.size());
  for (const auto& [t, tile] : want) {
    EXPECT_EQ(got.at(t).offsets, tile.offsets) << "tile " << t;
    EXPECT_EQ(got.at(t).vertices, tile.vertices) << "tile " << t;
  }
}

EngineOptions Verifying(double fraction, uint64_t seed) {
  EngineOptions options = InlineOptions();
  options.scheduler.verify_fraction = fraction;
  options.scheduler.verify_seed = seed;
  return options;
}

void ExpectCompleteProgress(const JobProgress& p) {
  EXPECT_EQ(p.tiles_done, p.tiles_total);
  EXPECT_EQ(p.samples_done, p.samples_total);  // nothing counted twice, nothing lost
  EXPECT_EQ(p.tile_samples_total, p.samples_total);
}

TEST(BakeEngineVerification, TwoHonestWorkersAgreeOnEveryTaskAndBakeTheSameTiles) {
  const auto plan = SmallPlan(4, 6, 0, 0, /*group_size=*/2);
  auto output = std::make_shared<RecordingOutput>();
  BakeEngine engine(Verifying(1.0, 7));
  ASSERT_TRUE(engine.AddJob(Job(plan, output, 2)).ok());
  EXPECT_EQ(RunFarm(engine, *plan, {"a", "b"}), 12);  // 6 tasks, each run twice
  ASSERT_EQ(output->end(), JobEnd::kSucceeded) << output->status();
  ExpectSameTiles(output->tiles(), Reference(plan, 2));
  const SchedulerStats stats = engine.Stats().scheduler;
  EXPECT_EQ(stats.tasks_verified, 6);
  EXPECT_EQ(stats.verification_mismatches, 0);
  EXPECT_EQ(stats.workers_quarantined, 0);
  EXPECT_EQ(output->progress().tasks_done, 6);  // merged once each
  ExpectCompleteProgress(output->progress());
}

TEST(BakeEngineVerification, AnOutvotedLiarIsQuarantinedAndItsGroupsAreBakedAgain) {
  const auto plan = SmallPlan(4, 6, 0, 0, /*group_size=*/2);
  auto output = std::make_shared<RecordingOutput>();
  EngineOptions options = Verifying(1.0, 7);
  std::vector<std::pair<std::string, std::string>> quarantined;
  options.on_quarantine = [&](const std::string& worker, const std::string& why) {
    quarantined.emplace_back(worker, why);
  };
  BakeEngine engine(std::move(options));
  ASSERT_TRUE(engine.AddJob(Job(plan, output, 2)).ok());
  RunFarm(engine, *plan, {"liar", "a", "b"}, {"liar"});
  ASSERT_EQ(output->end(), JobEnd::kSucceeded) << output->status();
  ExpectSameTiles(output->tiles(), Reference(plan, 2));
  ASSERT_EQ(quarantined.size(), 1u);
  EXPECT_EQ(quarantined[0].first, "liar");
  EXPECT_THAT(quarantined[0].second, HasSubstr("differs from the one two other workers agree on"));
  const SchedulerStats stats = engine.Stats().scheduler;
  EXPECT_EQ(stats.workers_quarantined, 1);
  EXPECT_GE(stats.verification_mismatches, 1);
  ExpectCompleteProgress(output->progress());
}

TEST(BakeEngineVerification, TilesALiarFedUnverifiedAreWithdrawnAndBakedAgain) {
  // 30 % of the tasks verified: the liar's other results are merged and stored unchecked until a
  // verified one convicts it; then every stored tile it fed is withdrawn and recomputed.
  const auto plan = SmallPlan(12, 4, 0, 0, /*group_size=*/1);
  auto output = std::make_shared<RecordingOutput>();
  BakeEngine engine(Verifying(0.3, 27));
  ASSERT_TRUE(engine.AddJob(Job(plan, output, 2)).ok());
  RunFarm(engine, *plan, {"liar", "a", "b"}, {"liar"});
  ASSERT_EQ(output->end(), JobEnd::kSucceeded) << output->status();
  EXPECT_EQ(engine.Stats().scheduler.workers_quarantined, 1);
  EXPECT_GT(output->withdrawn(), 0);
  EXPECT_EQ(output->progress().tiles_recomputed, output->withdrawn());
  ExpectSameTiles(output->tiles(), Reference(plan, 2));
  ExpectCompleteProgress(output->progress());
}

TEST(BakeEngineVerification, ALoneWorkerStillFinishesWithEveryTaskDrawn) {
  const auto plan = SmallPlan(3, 4);
  auto output = std::make_shared<RecordingOutput>();
  BakeEngine engine(Verifying(1.0, 7));
  ASSERT_TRUE(engine.AddJob(Job(plan, output, 2)).ok());
  EXPECT_EQ(RunFarm(engine, *plan, {"only"}), 6);
  ASSERT_EQ(output->end(), JobEnd::kSucceeded) << output->status();
  EXPECT_EQ(engine.Stats().scheduler.tasks_unverified, 6);
  ExpectSameTiles(output->tiles(), Reference(plan, 2));
}

TEST(BakeEngineVerification, AVoteNobodyCanGiveAnyMoreIsAcceptedAtTheTick) {
  const auto plan = SmallPlan(1, 2);
  auto output = std::make_shared<RecordingOutput>();
  int64_t now = 0;
  EngineOptions options = Verifying(1.0, 7);
  options.now_ms = [&now] { return now; };
  BakeEngine engine(std::move(options));
  ASSERT_TRUE(engine.AddJob(Job(plan, output, 2)).ok());
  const std::optional<TaskLease> lease = engine.Lease("a");
  ASSERT_TRUE(lease);
  EXPECT_FALSE(engine.Lease("b"));  // b is seen: it could verify
  ASSERT_TRUE(engine.Report("a", lease->lease_id, LeaseEvents(*plan, *lease)));
  engine.Tick();
  EXPECT_EQ(output->ended(), 0);  // waiting for b's vote
  now = 40'000;                   // b has gone silent
  engine.Tick();
  ASSERT_EQ(output->end(), JobEnd::kSucceeded) << output->status();
  EXPECT_EQ(engine.Stats().scheduler.tasks_unverified, 1);
  ExpectSameTiles(output->tiles(), Reference(plan, 2));
}

}  // namespace
}  // namespace pdsm
