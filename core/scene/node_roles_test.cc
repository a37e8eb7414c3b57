// Roles per node (core/scene/node_roles.h) as the mesh readers apply them: LoadMeshFileByRole
// splits a file by the roles its nodes' extras set, children inheriting; a file without roles
// is read exactly as LoadMeshFile reads it.
#include "core/scene/node_roles.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/scene/lightmap_parts.h"
#include "core/scene/mesh_file.h"
#include "tests/alpha_card.h"
#include "tests/role_world.h"
#include "tests/test_support.h"

namespace pdsm {
namespace {

using ::testing::HasSubstr;

class NodeRolesTest : public ::testing::Test {
 protected:
  std::string Write(const std::string& name, const std::string& contents) {
    const std::filesystem::path path = dir_.File(name);
    std::ofstream(path, std::ios::binary) << contents;
    return path.string();
  }

  testing::TempDir dir_;
};

// The x range of a part's vertices, to tell the quads apart.
std::pair<double, double> XRange(const MeshFileData& part) {
  double lo = 1e9, hi = -1e9;
  for (const glm::dvec3& p : part.positions) {
    lo = std::min(lo, p.x);
    hi = std::max(hi, p.x);
  }
  return {lo, hi};
}

TEST_F(NodeRolesTest, AFileIsSplitByItsNodesRolesAndChildrenInheritTheirParents) {
  const std::string path = Write("roles.gltf", testing::RoleWorldGltf("\"CASTER_ONLY\""));
  absl::StatusOr<std::vector<MeshFileData>> parts = LoadMeshFileByRole(path, "ctx");
  ASSERT_TRUE(parts.ok()) << parts.status();
  // The order: no role (the wall), then CASTER_ONLY (the roof, by its parent), RECEIVER_ONLY.
  ASSERT_EQ(parts->size(), 3u);
  EXPECT_FALSE((*parts)[0].node_role.has_value());
  EXPECT_EQ((*parts)[1].node_role, MeshRole::kCasterOnly);
  EXPECT_EQ((*parts)[2].node_role, MeshRole::kReceiverOnly);
  EXPECT_EQ(XRange((*parts)[0]), std::make_pair(-2.5, -0.5));
  EXPECT_EQ(XRange((*parts)[1]), std::make_pair(0.5, 2.5));
  EXPECT_EQ(XRange((*parts)[2]), std::make_pair(-3.0, 3.0));
  for (const MeshFileData& part : *parts) EXPECT_EQ(part.indices.size(), 6u);
}

TEST_F(NodeRolesTest, NodesOfOneRoleAreOnePart) {
  // The roof inherits RECEIVER_ONLY from its group, as the ground says itself.
  const std::string path = Write("roles.gltf", testing::RoleWorldGltf("\"RECEIVER_ONLY\""));
  absl::StatusOr<std::vector<MeshFileData>> parts = LoadMeshFileByRole(path, "ctx");
  ASSERT_TRUE(parts.ok()) << parts.status();
  ASSERT_EQ(parts->size(), 2u);
  EXPECT_FALSE((*parts)[0].node_role.has_value());
  EXPECT_EQ((*parts)[1].node_role, MeshRole::kReceiverOnly);
  EXPECT_EQ((*parts)[0].indices.size(), 6u);
  EXPECT_EQ((*parts)[1].indices.size(), 12u);
  EXPECT_EQ(XRange((*parts)[1]), std::make_pair(-3.0, 3.0));
}

// The bake reads every mesh path through LoadMeshFileByRole: a file without roles must give
// LoadMeshFile's bytes, or every existing bake's output would change.
void ExpectReadAsLoadMeshFile(const std::string& path) {
  absl::StatusOr<std::vector<MeshFileData>> parts = LoadMeshFileByRole(path, "ctx");
  absl::StatusOr<MeshFileData> whole = LoadMeshFile(path, "ctx");
  ASSERT_TRUE(parts.ok()) << parts.status();
  ASSERT_TRUE(whole.ok()) << whole.status();
  ASSERT_EQ(parts->size(), 1u) << path;
  const MeshFileData& part = parts->front();
  EXPECT_FALSE(part.node_role.has_value());
  EXPECT_EQ(part.positions, whole->positions) << path;
  EXPECT_EQ(part.indices, whole->indices) << path;
  EXPECT_EQ(part.uvs, whole->uvs) << path;
  EXPECT_EQ(part.triangle_masks, whole->triangle_masks) << path;
  EXPECT_EQ(part.masks.size(), whole->masks.size()) << path;
  EXPECT_EQ(part.warnings, whole->warnings) << path;
}

TEST_F(NodeRolesTest, AFileWithoutRolesIsReadAsLoadMeshFileReadsIt) {
  ExpectReadAsLoadMeshFile(Write("plain.gltf", testing::RoleWorldGltf("", /*ground_role=*/false)));
  ExpectReadAsLoadMeshFile(Write("card.gltf", testing::AlphaCardGltf()));
  ExpectReadAsLoadMeshFile(Write("two.obj",
                                 "o quad\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n"
                                 "o tri\nv 0 0 5\nv 2 0 5\nv 0 2 5\nf 5 6 7\nf 5 6 7\n"));
  ExpectReadAsLoadMeshFile(Write("tri.ply",
                                 "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\n"
                                 "property float y\nproperty float z\nelement face 2\n"
                                 "property list uchar int vertex_indices\nend_header\n"
                                 "0 0 0\n1 0 0\n1 1 0\n0 1 0.5\n3 0 1 2\n4 0 1 2 3\n"));
  ExpectReadAsLoadMeshFile(PDSM_SOURCE_DIR "/examples/world/world.gltf");
  ExpectReadAsLoadMeshFile(PDSM_SOURCE_DIR "/examples/foliage/cards.gltf");
  // The test meshes, where ../shared is present: the dragon as the benchmarks bake it.
  for (const char* model :
       {"/models/bun_zipper.ply", "/models/dragon_vrip_res3.ply", "/models/foliage.ply"}) {
    const std::string path = std::string(PDSM_SHARED_DIR) + model;
    if (std::filesystem::exists(path)) ExpectReadAsLoadMeshFile(path);
  }
}

TEST_F(NodeRolesTest, ARoleThatIsNotARoleNameIsNamedWithItsNodeAndFile) {
  const std::string path = Write("bad.gltf", testing::RoleWorldGltf("\"receiver\""));
  absl::StatusOr<std::vector<MeshFileData>> parts =
      LoadMeshFileByRole(path, "scene.json: meshes[0].path");
  ASSERT_FALSE(parts.ok());
  EXPECT_EQ(parts.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(parts.status().message(), HasSubstr("scene.json: meshes[0].path: cannot read"));
  EXPECT_THAT(parts.status().message(), HasSubstr("bad.gltf"));
  EXPECT_THAT(parts.status().message(),
              HasSubstr("node \"props\" extras.role: must be CASTER_AND_RECEIVER, CASTER_ONLY or "
                        "RECEIVER_ONLY (got \"receiver\")"));

  const std::string number = Write("number.gltf", testing::RoleWorldGltf("3"));
  parts = LoadMeshFileByRole(number, "ctx");
  ASSERT_FALSE(parts.ok());
  EXPECT_THAT(parts.status().message(), HasSubstr("node \"props\" extras.role: must be a string"));
  // The shadowmask's reader of the same nodes refuses it the same way.
  EXPECT_THAT(LoadLightmapParts(number, "ctx").status().message(),
              HasSubstr("node \"props\" extras.role: must be a string"));
}

TEST_F(NodeRolesTest, LightmapPartsCarryTheirNodesRoles) {
  const std::string path = Write("roles.gltf", testing::RoleWorldGltf("\"CASTER_ONLY\""));
  absl::StatusOr<std::vector<LightmapPart>> parts = LoadLightmapParts(path, "ctx");
  ASSERT_TRUE(parts.ok()) << parts.status();
  ASSERT_EQ(parts->size(), 3u);
  EXPECT_EQ((*parts)[0].node, "ground");
  EXPECT_EQ((*parts)[0].node_role, MeshRole::kReceiverOnly);
  EXPECT_EQ((*parts)[1].node, "roof");
  EXPECT_EQ((*parts)[1].node_role, MeshRole::kCasterOnly);
  EXPECT_EQ((*parts)[2].node, "wall");
  EXPECT_FALSE((*parts)[2].node_role.has_value());
}

}  // namespace
}  // namespace pdsm
