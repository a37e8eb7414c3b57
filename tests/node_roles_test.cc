// Roles per node (issue #16 item 1; core/scene/node_roles.h) as a user meets them: a glTF world
// whose nodes say RECEIVER_ONLY or CASTER_ONLY in their extras bakes with those roles through
// `pdsm bake WORLD.gltf` and a scene JSON alike, a receiver-only node casts no shadow, and
// `pdsm shadowmask` writes textures for the receiving nodes only.
#include <filesystem>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "absl/strings/str_cat.h"
#include "tests/role_world.h"
#include "tests/test_support.h"

namespace pdsm::testing {
namespace {

using ::testing::HasSubstr;

const std::string kPdsm = PDSM_CLI;

// Under the roof's middle, under the wall's middle, and in the open.
constexpr char kPoints[] = "1.5,0,0\n-1.5,0,0\n0,0,2.5\n";

// `pdsm bake FILE` (a world file or a scene JSON) and `pdsm query` at kPoints: the query's
// stdout.
std::string BakeAndQuery(const TempDir& dir, const std::string& scene) {
  const std::string out = dir.File("out.exr");
  const CommandResult bake =
      RunCommand(absl::StrCat(kPdsm, " bake ", scene, " -o ", out,
                              " --resolution 64x64 --samples 8 --sm-resolution 256"),
                 dir);
  EXPECT_EQ(bake.exit_code, 0) << bake.err;
  WriteText(dir.File("points.csv"), kPoints);
  const CommandResult query =
      RunCommand(absl::StrCat(kPdsm, " query ", out, " --points ", dir.File("points.csv")), dir);
  EXPECT_EQ(query.exit_code, 0) << query.err;
  return query.out;
}

TEST(NodeRoles, AReceiverOnlyNodeCastsNoShadowAndItsChildrenInheritIt) {
  TempDir dir;
  // The roof's group says RECEIVER_ONLY: the roof casts nothing, the wall (no role) does.
  WriteText(dir.File("roles.gltf"), RoleWorldGltf("\"RECEIVER_ONLY\""));
  EXPECT_EQ(BakeAndQuery(dir, dir.File("roles.gltf")),
            "1.5,0,0,0.000000\n-1.5,0,0,1.000000\n0,0,2.5,0.000000\n");
  // The same world without the group's role: the roof casts (the test can tell them apart).
  WriteText(dir.File("plain.gltf"), RoleWorldGltf(""));
  EXPECT_EQ(BakeAndQuery(dir, dir.File("plain.gltf")),
            "1.5,0,0,1.000000\n-1.5,0,0,1.000000\n0,0,2.5,0.000000\n");
}

TEST(NodeRoles, ANodesRoleWinsOverItsSceneEntrysRole) {
  TempDir dir;
  WriteText(dir.File("roles.gltf"), RoleWorldGltf("\"CASTER_AND_RECEIVER\""));
  // The entry says RECEIVER_ONLY: the wall (no role of its own) casts nothing; the roof's
  // group says CASTER_AND_RECEIVER, so the roof casts.
  WriteText(dir.File("scene.json"),
            R"({"name": "roles", "meshes": [{"path": "roles.gltf", "role": "RECEIVER_ONLY"}],)"
            R"( "light": {"sun": {"direction": [0, -1, 0], "angularDiameterDeg": 2}}})");
  EXPECT_EQ(BakeAndQuery(dir, dir.File("scene.json")),
            "1.5,0,0,1.000000\n-1.5,0,0,0.000000\n0,0,2.5,0.000000\n");
}

TEST(NodeRoles, ShadowmaskTexturesAreWrittenForReceivingNodesOnly) {
  TempDir dir;
  // The roof is CASTER_ONLY (by its group): it gets no texture; the ground and the wall do.
  WriteText(dir.File("roles.gltf"), RoleWorldGltf("\"CASTER_ONLY\""));
  const std::string out = dir.File("roles.exr");
  const CommandResult bake =
      RunCommand(absl::StrCat(kPdsm, " bake ", dir.File("roles.gltf"), " -o ", out,
                              " --resolution 32x32 --samples 4"),
                 dir);
  ASSERT_EQ(bake.exit_code, 0) << bake.err;
  const std::string masks = dir.File("masks");
  const CommandResult shadowmask = RunCommand(
      absl::StrCat(kPdsm, " shadowmask ", dir.File("roles.gltf"), " --pdsm ", out, " -o ", masks),
      dir);
  ASSERT_EQ(shadowmask.exit_code, 0) << shadowmask.err;
  EXPECT_TRUE(std::filesystem::exists(masks + "/ground-shadowmask0.exr"));
  EXPECT_TRUE(std::filesystem::exists(masks + "/wall-shadowmask0.exr"));
  EXPECT_FALSE(std::filesystem::exists(masks + "/roof-shadowmask0.exr"));
}

TEST(NodeRoles, ABadRoleIsNamedWithTheFileAndTheNode) {
  TempDir dir;
  WriteText(dir.File("bad.gltf"), RoleWorldGltf("\"receiver\""));
  const CommandResult bake = RunCommand(
      absl::StrCat(kPdsm, " bake ", dir.File("bad.gltf"), " -o ", dir.File("bad.exr")), dir);
  EXPECT_NE(bake.exit_code, 0);
  EXPECT_THAT(bake.err, HasSubstr("bad.gltf"));
  EXPECT_THAT(bake.err, HasSubstr("node \"props\" extras.role: must be CASTER_AND_RECEIVER, "
                                  "CASTER_ONLY or RECEIVER_ONLY (got \"receiver\")"));
  EXPECT_FALSE(std::filesystem::exists(dir.File("bad.exr")));
}

// `pdsm submit` sends a file split by roles as several entries; a later entry's error still
// names the entry the user wrote (checked before anything is sent: no server needed).
TEST(NodeRoles, SubmitNamesTheScenesOwnEntryAfterAFileSplitByRoles) {
  TempDir dir;
  WriteText(dir.File("roles.gltf"), RoleWorldGltf("\"CASTER_ONLY\""));
  WriteText(dir.File("scene.json"),
            R"({"name": "roles", "meshes": [{"path": "roles.gltf"}, {"inline": {"positions":)"
            R"( [0, 0, 0, 1, 0, 0, 0, 0, 1], "indices": [0, 1, 2]}, "transform": [1, 2, 3]}],)"
            R"( "light": {"sun": {"direction": [0, -1, 0], "angularDiameterDeg": 2}}})");
  const CommandResult submit = RunCommand(
      absl::StrCat(kPdsm, " submit ", dir.File("scene.json"), " --server 127.0.0.1:1"), dir);
  EXPECT_NE(submit.exit_code, 0);
  EXPECT_THAT(submit.err, HasSubstr("scene.json: meshes[1].transform: must have 0 or 16 numbers"));
}

}  // namespace
}  // namespace pdsm::testing
