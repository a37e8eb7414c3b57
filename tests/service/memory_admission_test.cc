// The coordinator's memory for plans (--max-planned-mib, server/plan_budget.h) on the real
// service: jobs whose plans do not fit beside the running ones' wait QUEUED without them,
// saying why; they run in turn as memory is released, across a coordinator restart, and bake
// the same bytes as `pdsm bake`; a waiting job cancels at once; a job that can never fit is
// refused naming the flag.
#include <csignal>
#include <string>

#include <gtest/gtest.h>

#include "absl/strings/str_cat.h"

#include "tests/service/service_cluster.h"

namespace pdsm::testing {
namespace {

using std::chrono::seconds;

// A surfaces-only bake over a 40 x 40 ground of 200 x 200 quads (an OBJ, uploaded as an
// asset): its plan keeps the ground's 40,401 vertices and 80,000 triangles, 1.4 MB, which
// the coordinator counts against --max-planned-mib; a small square casts.
std::string WriteGroundScene(const TempDir& dir) {
  constexpr int kSide = 200;
  std::string obj;
  for (int j = 0; j <= kSide; ++j) {
    for (int i = 0; i <= kSide; ++i) {
      absl::StrAppend(&obj, "v ", 40.0 * i / kSide - 20, " 0 ", 40.0 * j / kSide - 20, "\n");
    }
  }
  for (int j = 0; j < kSide; ++j) {
    for (int i = 0; i < kSide; ++i) {
      const int a = j * (kSide + 1) + i + 1, b = a + 1, c = a + kSide + 1, d = c + 1;
      absl::StrAppend(&obj, "f ", a, " ", c, " ", b, "\nf ", b, " ", c, " ", d, "\n");
    }
  }
  WriteText(dir.File("ground.obj"), obj);
  const std::string path = dir.File("ground.json");
  WriteText(path, R"({
  "name": "ground",
  "meshes": [
    {"path": "ground.obj", "role": "RECEIVER_ONLY"},
    {"inline": {"positions": [-0.5,2,-0.5, 0.5,2,-0.5, 0.5,2,0.5, -0.5,2,0.5],
                "indices": [0,1,2, 0,2,3]}}
  ],
  "light": {"rect": {"center": [0,10,0], "normal": [0,-1,0], "up": [0,0,1], "size": [1,1]}},
  "bake": {"resolution": [256,256], "samples": 4, "tileSize": 16, "surfacesOnly": true}
})");
  return path;
}

bool Waits(const pdsm::v1::Job& job) {
  return job.state() == pdsm::v1::QUEUED &&
         job.queued_reason().find("waiting for coordinator memory") != std::string::npos;
}

TEST(MemoryAdmission, JobsThatDoNotFitWaitTheirTurnAcrossARestartAndBakeExactly) {
  // One such job fits in 2 MiB, two do not.
  ServiceCluster cluster(CoordinatorArgs({"--max-planned-mib", "2"}));
  ASSERT_TRUE(cluster.StartCoordinator());
  const std::string scene = WriteGroundScene(cluster.dir());
  const std::string expected = LocalBakeBytes(cluster.dir(), scene);

  // No worker yet: nothing ends, so what is held stays held.
  const std::string first = cluster.Submit(scene);
  pdsm::v1::Stats stats = cluster.Stats();
  EXPECT_GT(stats.planned_bytes(), 40401 * 12 + 80000 * 12) << "the ground is held";
  EXPECT_LE(stats.planned_bytes(), int64_t{2} << 20) << "more than the ground is held";
  EXPECT_EQ(stats.max_planned_bytes(), int64_t{2} << 20);
  const std::string second = cluster.Submit(scene);
  const std::string third = cluster.Submit(scene);
  pdsm::v1::Job job;
  ASSERT_TRUE(cluster.GetJob(first, &job).ok());
  EXPECT_EQ(job.queued_reason(), "");
  EXPECT_FALSE(job.plan_fingerprint().empty());
  ASSERT_TRUE(cluster.GetJob(second, &job).ok());
  EXPECT_TRUE(Waits(job)) << job.queued_reason();
  EXPECT_EQ(job.plan_fingerprint(), "") << "a waiting job holds no plan";
  EXPECT_EQ(job.tiles_total(), 256) << "sized from its scene all the same";
  ASSERT_TRUE(cluster.GetJob(third, &job).ok());
  EXPECT_TRUE(Waits(job)) << job.queued_reason();
  EXPECT_NE(job.queued_reason().find("1 job waits ahead of it"), std::string::npos)
      << job.queued_reason();
  stats = cluster.Stats();
  EXPECT_EQ(stats.jobs_waiting_for_memory(), 2);
  EXPECT_EQ(stats.jobs_queued(), 3);
  const CommandResult status = cluster.Pdsm("status " + third);
  EXPECT_NE(status.out.find("waiting for coordinator memory"), std::string::npos) << status.out;

  // A waiting job cancels at once, and never runs.
  const CommandResult cancel = cluster.Pdsm("cancel " + second);
  EXPECT_NE(cancel.out.find("CANCELLED"), std::string::npos) << cancel.out << cancel.err;

  // A restart resumes the first, and the third waits again.
  cluster.coordinator().Signal(SIGKILL);
  cluster.coordinator().Wait(seconds(10));
  ASSERT_TRUE(cluster.StartCoordinator()) << cluster.Log("coordinator.log");
  ASSERT_TRUE(cluster.GetJob(third, &job).ok());
  EXPECT_TRUE(Waits(job)) << job.queued_reason();
  ASSERT_TRUE(cluster.GetJob(first, &job).ok());
  EXPECT_EQ(job.queued_reason(), "");

  cluster.AddWorker();
  for (const std::string& id : {first, third}) {
    const pdsm::v1::Job ended = cluster.WaitForEnd(id);
    ASSERT_EQ(ended.state(), pdsm::v1::SUCCEEDED) << ended.error();
    EXPECT_TRUE(FetchBytes(cluster, id) == expected) << "job " << id << " differs from pdsm bake";
  }
  ASSERT_TRUE(cluster.GetJob(second, &job).ok());
  EXPECT_EQ(job.state(), pdsm::v1::CANCELLED);
  EXPECT_EQ(job.tiles_done(), 0);
  stats = cluster.Stats();
  EXPECT_EQ(stats.planned_bytes(), 0) << "every job ended: nothing is held";
  EXPECT_EQ(stats.jobs_waiting_for_memory(), 0);
}

TEST(MemoryAdmission, AJobThatCanNeverFitIsRefusedNamingTheFlag) {
  ServiceCluster cluster(CoordinatorArgs({"--max-planned-mib", "1"}));
  ASSERT_TRUE(cluster.StartCoordinator());
  const CommandResult r = cluster.Pdsm("submit " + WriteGroundScene(cluster.dir()));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("above its limit of 1.0 MiB (--max-planned-mib)"), std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("bake.surfacesOnly off"), std::string::npos) << r.err;
  EXPECT_EQ(cluster.Stats().planned_bytes(), 0);
}

}  // namespace
}  // namespace pdsm::testing
