// Verification by redundancy on a real service (issue #17 item 3): a worker whose results are
// well-formed and plausible but wrong passes every check a single result allows; with
// --verify-fraction the coordinator runs tasks twice, outvotes it, quarantines it and bakes
// again what it fed, so the fetched file is still the local bake's, byte for byte.
#include <chrono>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include "tests/service/service_cluster.h"

namespace pdsm::testing {
namespace {

using std::chrono::seconds;

TEST(Verification, APlausibleLiarIsOutvotedQuarantinedAndTheBakeStaysExact) {
  ServiceCluster cluster(CoordinatorArgs({"--verify-fraction", "1"}));
  ASSERT_TRUE(cluster.StartCoordinator());
  const std::string scene = WriteServiceScene(cluster.dir(), 64, 16, 32);
  const std::string expected = LocalBakeBytes(cluster.dir(), scene);
  const std::string job_id = cluster.Submit(scene);
  const auto workers = cluster.WorkersStub();

  // The liar takes the first task, so its answer is the one merged.
  const std::optional<pdsm::v1::Task> leased = LeaseOneTask(cluster, "liar");
  ASSERT_TRUE(leased) << "no task leased";
  const pdsm::v1::Task task = *leased;

  // Two honest workers join; the liar answers once both are active, so that its result waits
  // for their votes instead of being accepted unverified.
  cluster.AddWorker();
  cluster.AddWorker();
  const auto deadline = std::chrono::steady_clock::now() + seconds(60) * TestTimeScale();
  while (cluster.Stats().workers_active() < 3 && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ASSERT_GE(cluster.Stats().workers_active(), 3);

  // Every pixel lit: no count outside its batch, no depth out of range; only wrong.
  pdsm::v1::ReportResultRequest lie;
  lie.set_worker_id("liar");
  lie.set_lease_id(task.lease_id());
  lie.set_seconds(1.0);
  for (int i = 0; i < task.tile_indices_size(); ++i) {
    pdsm::v1::TileEventsData* tile = lie.add_tiles();
    for (int p = 0; p <= 32 * 32; ++p) tile->add_offsets(0);
  }
  {
    grpc::ClientContext context;
    PrepareCall(&context, "", seconds(10));
    pdsm::v1::ReportResultResponse response;
    ASSERT_TRUE(workers->ReportResult(&context, lie, &response).ok());
    EXPECT_TRUE(response.accepted()) << "a lie looks like any result to the one telling it";
  }

  const pdsm::v1::Job job = cluster.WaitForEnd(job_id);
  ASSERT_EQ(job.state(), pdsm::v1::SUCCEEDED) << job.error();
  const std::string out = cluster.dir().File("fetched.exr");
  ASSERT_EQ(cluster.Pdsm("fetch " + job_id + " -o " + out).exit_code, 0);
  EXPECT_TRUE(ReadBytes(out) == expected) << "the lie reached the PDSM";
  const pdsm::v1::Stats stats = cluster.Stats();
  EXPECT_EQ(stats.workers_quarantined(), 1);
  EXPECT_GE(stats.verification_mismatches(), 1);
  EXPECT_GT(stats.tasks_verified(), 0);
  EXPECT_NE(cluster.Log("coordinator.log").find("worker liar quarantined by verification"),
            std::string::npos)
      << cluster.Log("coordinator.log");
  // Asking for more work is refused in a way a pdsm-worker does not retry: it exits saying why.
  grpc::ClientContext context;
  PrepareCall(&context, "", seconds(10));
  pdsm::v1::LeaseTaskRequest request;
  request.set_worker_id("liar");
  pdsm::v1::LeaseTaskResponse response;
  const grpc::Status refused = workers->LeaseTask(&context, request, &response);
  EXPECT_EQ(refused.error_code(), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_NE(refused.error_message().find("quarantined"), std::string::npos)
      << refused.error_message();
}

}  // namespace
}  // namespace pdsm::testing
