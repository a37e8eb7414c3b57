// pdsm-view --server --job: waits for a job on a real coordinator and worker, fetches its PDSM
// and shows the same image as the local bake of the same scene.
#include <string>

#include <gtest/gtest.h>

#include "tests/service/service_cluster.h"
#include "tests/view/view_test_support.h"

namespace pdsm::testing {
namespace {

// examples/plates with a bake small enough for a test (48x48 pixels, 8 samples).
std::string WriteSmallPlates(const TempDir& dir) {
  std::string scene = ReadBytes(ExamplePath("plates"));
  const std::string from = "\"resolution\": [256,256], \"samples\": 64";
  EXPECT_NE(scene.find(from), std::string::npos);
  scene.replace(scene.find(from), from.size(), "\"resolution\": [48,48], \"samples\": 8");
  WriteText(dir.File("plates.json"), scene);
  return dir.File("plates.json");
}

TEST(ViewServer, JobOnTheServiceLooksLikeTheLocalBake) {
  ClusterOptions options;
  options.client_token = "client-secret";
  options.worker_token = "worker-secret";
  ServiceCluster cluster(options);
  ASSERT_TRUE(cluster.StartCoordinator()) << cluster.Log("coordinator.log");
  cluster.AddWorker();
  const std::string scene = WriteSmallPlates(cluster.dir());
  const std::string job_id = cluster.Submit(scene);
  ASSERT_EQ(job_id.size(), 16u);

  // Started at once: the viewer waits for the job to finish (WatchJob), then fetches.
  const std::string view_args = " --headless --size 96x72 --screenshot ";
  CommandResult remote = RunCommand(
      std::string(PDSM_VIEW) + " " + scene + " --server " + cluster.address() + " --job " +
          job_id + " --token-file " + cluster.dir().File("client_token") + view_args +
          cluster.dir().File("remote.png") + " --save-attenuation " +
          cluster.dir().File("remote.pfm"),
      cluster.dir());
  ASSERT_EQ(remote.exit_code, 0) << remote.err << cluster.Log("coordinator.log");
  EXPECT_NE(remote.err.find("SUCCEEDED"), std::string::npos) << remote.err;

  CommandResult bake = RunCommand(std::string(PDSM_CLI) + " bake " + scene + " -o " +
                                      cluster.dir().File("local.exr") + " --no-preview",
                                  cluster.dir());
  ASSERT_EQ(bake.exit_code, 0) << bake.err;
  CommandResult local = RunCommand(std::string(PDSM_VIEW) + " " + scene + " --pdsm " +
                                       cluster.dir().File("local.exr") + view_args +
                                       cluster.dir().File("local.png") + " --save-attenuation " +
                                       cluster.dir().File("local.pfm"),
                                   cluster.dir());
  ASSERT_EQ(local.exit_code, 0) << local.err;
  // The service's PDSM has the local bake's bytes, so the renders are identical.
  EXPECT_TRUE(ReadBytes(cluster.dir().File("remote.pfm")) ==
              ReadBytes(cluster.dir().File("local.pfm")));

  // A wrong token is refused before anything is drawn.
  WriteText(cluster.dir().File("bad_token"), "nope\n");
  CommandResult refused = RunCommand(
      std::string(PDSM_VIEW) + " " + scene + " --server " + cluster.address() + " --job " +
          job_id + " --token-file " + cluster.dir().File("bad_token") + view_args +
          cluster.dir().File("refused.png"),
      cluster.dir());
  EXPECT_NE(refused.exit_code, 0);
  EXPECT_FALSE(std::filesystem::exists(cluster.dir().File("refused.png")));
}

}  // namespace
}  // namespace pdsm::testing
