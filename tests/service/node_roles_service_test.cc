// Roles per node through the service (issue #16 item 1): `pdsm submit` splits a glTF whose
// nodes set roles into one mesh asset per role, each sent with its role, in the order the local
// bake splits it; the fetched file is `pdsm bake`'s, byte for byte.
#include <string>

#include <gtest/gtest.h>

#include "tests/role_world.h"
#include "tests/service/service_cluster.h"

namespace pdsm::testing {
namespace {

TEST(ServiceNodeRoles, ARoleWorldMatchesTheLocalBake) {
  ServiceCluster cluster(CoordinatorArgs({"--samples-per-task", "4"}));
  ASSERT_TRUE(cluster.StartCoordinator());
  WriteText(cluster.dir().File("roles.gltf"), RoleWorldGltf("\"RECEIVER_ONLY\""));
  const std::string scene = cluster.dir().File("roles.json");
  WriteText(scene, R"({"name": "roles", "meshes": [{"path": "roles.gltf"}],)"
                   R"( "light": {"sun": {"direction": [0, -1, 0], "angularDiameterDeg": 2}},)"
                   R"( "bake": {"resolution": [64, 64], "samples": 8, "tileSize": 16}})");
  const pdsm::v1::Job job = ExpectServiceBakesAsLocal(cluster, scene);
  ASSERT_EQ(job.state(), pdsm::v1::SUCCEEDED);
  // The roof (RECEIVER_ONLY by its group) casts nothing, the wall (no role: the entry's) does:
  // a service that lost the roles would shadow the roof's footprint.
  const std::string points = cluster.dir().File("points.csv");
  WriteText(points, "1.5,0,0\n-1.5,0,0\n0,0,2.5\n");
  const CommandResult query = cluster.Pdsm("query --job " + job.job_id() + " --points " + points);
  ASSERT_EQ(query.exit_code, 0) << query.err;
  EXPECT_EQ(query.out, "1.5,0,0,0.000000\n-1.5,0,0,1.000000\n0,0,2.5,0.000000\n");
}

}  // namespace
}  // namespace pdsm::testing
