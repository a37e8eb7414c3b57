#include "core/scene/mesh_file.h"

#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "absl/strings/escaping.h"
#include "absl/strings/str_cat.h"
#include "tests/test_support.h"

namespace pdsm {
namespace {

using ::testing::HasSubstr;

class MeshFileTest : public ::testing::Test {
 protected:
  std::string Write(const std::string& name, const std::string& contents) {
    const std::filesystem::path path = dir_ / name;
    std::ofstream(path, std::ios::binary) << contents;
    return path.string();
  }

  ::pdsm::testing::TempDir temp_dir_;  // a fresh folder per test, removed after it
  const std::filesystem::path dir_ = temp_dir_.path();
};

TEST_F(MeshFileTest, ObjQuadAndTriangleAreTriangulatedAndFlattened) {
  // Two objects: a quad (two triangles) and a triangle; indices are 1-based in OBJ.
  const std::string path = Write("two.obj",
                                 "o quad\n"
                                 "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                                 "f 1 2 3 4\n"
                                 "o tri\n"
                                 "v 0 0 5\nv 2 0 5\nv 0 2 5\n"
                                 "f 5 6 7\n");
  absl::StatusOr<MeshFileData> mesh = LoadMeshFile(path, "test");
  ASSERT_TRUE(mesh.ok()) << mesh.status();
  ASSERT_EQ(mesh->indices.size(), 9u);
  for (uint32_t index : mesh->indices) ASSERT_LT(index, mesh->positions.size());

  double area_z0 = 0, area_z5 = 0;
  for (size_t t = 0; t < 3; ++t) {
    const glm::dvec3& a = mesh->positions[mesh->indices[3 * t]];
    const glm::dvec3& b = mesh->positions[mesh->indices[3 * t + 1]];
    const glm::dvec3& c = mesh->positions[mesh->indices[3 * t + 2]];
    const double area = 0.5 * glm::length(glm::cross(b - a, c - a));
    EXPECT_EQ(a.z, b.z);
    EXPECT_EQ(a.z, c.z);
    (a.z == 0 ? area_z0 : area_z5) += area;
  }
  EXPECT_DOUBLE_EQ(area_z0, 1.0);
  EXPECT_DOUBLE_EQ(area_z5, 2.0);
}

TEST_F(MeshFileTest, GltfNodeTransformIsApplied) {
  // One triangle, referenced by a node translated by (10, 20, 30) and scaled by 2.
  const float positions[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  const uint16_t indices[3] = {0, 1, 2};
  std::string bytes(sizeof(positions) + sizeof(indices) + 2, '\0');
  std::memcpy(bytes.data(), positions, sizeof(positions));
  std::memcpy(bytes.data() + sizeof(positions), indices, sizeof(indices));
  const std::string gltf =
      absl::StrCat(R"({
    "asset": {"version": "2.0"},
    "scene": 0,
    "scenes": [{"nodes": [0]}],
    "nodes": [{"mesh": 0, "translation": [10, 20, 30], "scale": [2, 2, 2]}],
    "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
    "buffers": [{"byteLength": )",
                   bytes.size(), R"(, "uri": "data:application/octet-stream;base64,)",
                   absl::Base64Escape(bytes), R"("}],
    "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36},
                    {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
    "accessors": [
      {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
       "min": [0, 0, 0], "max": [1, 1, 0]},
      {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}]
  })");
  const std::string path = Write("tri.gltf", gltf);
  absl::StatusOr<MeshFileData> mesh = LoadMeshFile(path, "test");
  ASSERT_TRUE(mesh.ok()) << mesh.status();
  ASSERT_EQ(mesh->indices.size(), 3u);
  ASSERT_EQ(mesh->positions.size(), 3u);
  std::vector<glm::dvec3> corners;
  for (uint32_t i : mesh->indices) corners.push_back(mesh->positions[i]);
  EXPECT_EQ(corners[0], glm::dvec3(10, 20, 30));
  EXPECT_EQ(corners[1], glm::dvec3(12, 20, 30));
  EXPECT_EQ(corners[2], glm::dvec3(10, 22, 30));
}

TEST_F(MeshFileTest, MissingFileNamesContextAndPath) {
  const std::string path = (dir_ / "nope.ply").string();
  absl::StatusOr<MeshFileData> mesh = LoadMeshFile(path, "scene.json: meshes[0].path");
  ASSERT_EQ(mesh.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(mesh.status().message(),
              HasSubstr(absl::StrCat("scene.json: meshes[0].path: cannot read \"", path, "\"")));
  EXPECT_THAT(mesh.status().message(), HasSubstr("no such file"));
}

TEST_F(MeshFileTest, GarbageFileIsInvalidArgument) {
  std::string garbage;
  for (int i = 0; i < 512; ++i) garbage.push_back(static_cast<char>((i * 7919 + 13) & 0xff));
  const std::string path = Write("garbage.ply", garbage);
  absl::StatusOr<MeshFileData> mesh = LoadMeshFile(path, "ctx: meshes[3].path");
  ASSERT_EQ(mesh.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(mesh.status().message(),
              HasSubstr(absl::StrCat("ctx: meshes[3].path: cannot read \"", path, "\": ")));
}

TEST_F(MeshFileTest, DirectoryIsInvalidArgument) {
  absl::StatusOr<MeshFileData> mesh = LoadMeshFile(dir_.string(), "ctx");
  ASSERT_EQ(mesh.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(mesh.status().message(), HasSubstr("not a regular file"));
}

TEST_F(MeshFileTest, FileWithoutTrianglesIsInvalidArgument) {
  // Only a line: triangulation leaves it alone and it casts no shadow.
  const std::string path = Write("line.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2\n");
  absl::StatusOr<MeshFileData> mesh = LoadMeshFile(path, "ctx");
  ASSERT_EQ(mesh.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(mesh.status().message(), HasSubstr(path));
}

TEST_F(MeshFileTest, SharedBunny) {
  const std::string path = PDSM_SHARED_DIR "/models/bun_zipper.ply";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " not present";
  absl::StatusOr<MeshFileData> mesh = LoadMeshFile(path, "bunny");
  ASSERT_TRUE(mesh.ok()) << mesh.status();
  EXPECT_EQ(mesh->indices.size(), 3u * 69451);
  // 35947 vertices in the file, of which 1113 no face uses (models/README.md); the importer
  // drops those.
  EXPECT_EQ(mesh->positions.size(), 35947u - 1113u);
  glm::dvec3 lo(1e30), hi(-1e30);
  for (const glm::dvec3& p : mesh->positions) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  // Bounding box from models/README.md.
  EXPECT_NEAR(lo.x, -0.0946899, 1e-6);
  EXPECT_NEAR(lo.y, 0.0329874, 1e-6);
  EXPECT_NEAR(lo.z, -0.0618736, 1e-6);
  EXPECT_NEAR(hi.x, 0.0610091, 1e-6);
  EXPECT_NEAR(hi.y, 0.187321, 1e-6);
  EXPECT_NEAR(hi.z, 0.0587997, 1e-6);
}

}  // namespace
}  // namespace pdsm
