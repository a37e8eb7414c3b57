// Alpha-tested casters through the service (issue #16 item 2): `pdsm submit` uploads a glTF
// whose card is alpha-tested as a version-2 mesh asset (its UVs and mask with it), every worker
// draws it with the alpha-tested program, and the fetched file is `pdsm bake`'s, byte for byte.
#include <string>

#include <gtest/gtest.h>

#include "tests/alpha_card.h"
#include "tests/service/service_cluster.h"

namespace pdsm::testing {
namespace {

TEST(ServiceAlphaTested, ACardWorldMatchesTheLocalBake) {
  ServiceCluster cluster(CoordinatorArgs({"--samples-per-task", "4"}));
  ASSERT_TRUE(cluster.StartCoordinator());
  WriteText(cluster.dir().File("card.gltf"), AlphaCardGltf());
  const std::string scene = cluster.dir().File("card.json");
  WriteText(scene, AlphaCardSceneJson("card.gltf", 64, 8));
  const pdsm::v1::Job job = ExpectServiceBakesAsLocal(cluster, scene);
  ASSERT_EQ(job.state(), pdsm::v1::SUCCEEDED);
  const std::string& job_id = job.job_id();
  // Under the card's hole the job answers lit, under its opaque half shadowed.
  const std::string points = cluster.dir().File("points.csv");
  WriteText(points, "0.6,0,0.5\n-0.6,0,0.5\n");
  const CommandResult query = cluster.Pdsm("query --job " + job_id + " --points " + points);
  ASSERT_EQ(query.exit_code, 0) << query.err;
  EXPECT_EQ(query.out, "0.6,0,0.5,0.000000\n-0.6,0,0.5,1.000000\n");
}

}  // namespace
}  // namespace pdsm::testing
