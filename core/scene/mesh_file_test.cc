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
#include "core/util/png_writer.h"
#include "tests/alpha_card.h"
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

// ---- Alpha-tested materials (tests/alpha_card.h) ----------------------------------------

// The triangles of `mesh` whose vertices all lie at y = kCardHeight: the card's.
std::vector<size_t> CardTriangles(const MeshFileData& mesh) {
  std::vector<size_t> card;
  for (size_t t = 0; t < mesh.indices.size() / 3; ++t) {
    if (mesh.positions[mesh.indices[3 * t]].y == testing::kCardHeight) card.push_back(t);
  }
  return card;
}

TEST_F(MeshFileTest, MaskMaterialKeepsItsUvsAndTextureAlpha) {
  const std::string path = Write("card.gltf", testing::AlphaCardGltf());
  absl::StatusOr<MeshFileData> mesh = LoadMeshFile(path, "ctx");
  ASSERT_TRUE(mesh.ok()) << mesh.status();
  ASSERT_EQ(mesh->masks.size(), 1u);
  const AlphaMask& mask = *mesh->masks[0];
  EXPECT_EQ(mask.width, 64);
  EXPECT_EQ(mask.height, 64);
  EXPECT_EQ(mask.cutoff, 0.5f);  // glTF's default alphaCutoff
  EXPECT_EQ(mask.wrap_u, TextureWrap::kClampToEdge);
  EXPECT_THAT(mask.label, HasSubstr("\"card\""));
  ASSERT_EQ(mesh->uvs.size(), mesh->positions.size());
  ASSERT_EQ(mesh->triangle_masks.size(), 4u);
  const std::vector<size_t> card = CardTriangles(*mesh);
  ASSERT_EQ(card.size(), 2u);
  for (size_t t = 0; t < 4; ++t) {
    const bool on_card = t == card[0] || t == card[1];
    EXPECT_EQ(mesh->triangle_masks[t], on_card ? 1 : 0) << "triangle " << t;
  }
  // glTF's UVs come through as the file holds them: u = (x + 1) / 2, v = (z + 1) / 2, v = 0 at
  // the image's top row.
  for (size_t t : card) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = mesh->indices[3 * t + k];
      const glm::dvec3& p = mesh->positions[v];
      EXPECT_EQ(mesh->uvs[v], glm::vec2((p.x + 1) / 2, (p.z + 1) / 2)) << "vertex " << v;
    }
  }
  EXPECT_TRUE(mask.CastsAt({0.25, 0.5}));    // u < 1/2: opaque
  EXPECT_FALSE(mask.CastsAt({0.75, 0.5}));   // clear
  EXPECT_TRUE(mask.CastsAt({0.75, 0.125}));  // v < 1/4 (the image's top rows): opaque
  EXPECT_TRUE(mesh->warnings.empty());
}

TEST_F(MeshFileTest, OpaqueMaterialsHaveNoMasks) {
  testing::AlphaCardOptions opaque;
  opaque.alpha_mode = "OPAQUE";
  absl::StatusOr<MeshFileData> mesh =
      LoadMeshFile(Write("card.gltf", testing::AlphaCardGltf(opaque)), "ctx");
  ASSERT_TRUE(mesh.ok()) << mesh.status();
  EXPECT_FALSE(mesh->has_masks());
  EXPECT_TRUE(mesh->uvs.empty());
  EXPECT_TRUE(mesh->triangle_masks.empty());
}

TEST_F(MeshFileTest, MaskWithoutTextureIsDecidedByTheFactorAlone) {
  // The issue's case: alpha 0.2 under the 0.5 cutoff casts nothing at all.
  testing::AlphaCardOptions faint;
  faint.texture = false;
  faint.factor_alpha = 0.2;
  absl::StatusOr<MeshFileData> mesh =
      LoadMeshFile(Write("faint.gltf", testing::AlphaCardGltf(faint)), "ctx");
  ASSERT_TRUE(mesh.ok()) << mesh.status();
  ASSERT_EQ(mesh->masks.size(), 1u);
  EXPECT_FALSE(mesh->masks[0]->CastsAt({0.5, 0.5}));
  EXPECT_FALSE(mesh->masks[0]->CastsAt({0.01, 0.99}));
  // It looks up no texture, so it needs no UVs.
  faint.texcoords = false;
  mesh = LoadMeshFile(Write("faint_bare.gltf", testing::AlphaCardGltf(faint)), "ctx");
  ASSERT_TRUE(mesh.ok()) << mesh.status();
  ASSERT_EQ(mesh->masks.size(), 1u);
  EXPECT_FALSE(mesh->masks[0]->CastsAt({0.5, 0.5}));
  faint.texcoords = true;
  // Alpha 0.8 passes everywhere: opaque.
  testing::AlphaCardOptions solid = faint;
  solid.factor_alpha = 0.8;
  mesh = LoadMeshFile(Write("solid.gltf", testing::AlphaCardGltf(solid)), "ctx");
  ASSERT_TRUE(mesh.ok()) << mesh.status();
  EXPECT_FALSE(mesh->has_masks());
}

TEST_F(MeshFileTest, TheFactorScalesTheTextureAgainstTheCutoff) {
  // alpha 255 * 0.5 = 0.5 >= 0.4: the opaque texels still cast; with cutoff 0.6, none do.
  testing::AlphaCardOptions half;
  half.factor_alpha = 0.5;
  half.alpha_cutoff = 0.4;
  absl::StatusOr<MeshFileData> mesh =
      LoadMeshFile(Write("half.gltf", testing::AlphaCardGltf(half)), "ctx");
  ASSERT_TRUE(mesh.ok()) << mesh.status();
  ASSERT_EQ(mesh->masks.size(), 1u);
  EXPECT_FLOAT_EQ(mesh->masks[0]->cutoff, 0.8f);
  EXPECT_TRUE(mesh->masks[0]->CastsAt({0.25, 0.5}));
  half.alpha_cutoff = 0.6;
  mesh = LoadMeshFile(Write("half.gltf", testing::AlphaCardGltf(half)), "ctx");
  ASSERT_TRUE(mesh.ok()) << mesh.status();
  ASSERT_EQ(mesh->masks.size(), 1u);
  EXPECT_FALSE(mesh->masks[0]->CastsAt({0.25, 0.5}));
}

TEST_F(MeshFileTest, BlendIsTestedAtOneHalfWithAWarning) {
  testing::AlphaCardOptions blend;
  blend.alpha_mode = "BLEND";
  blend.alpha_cutoff = 0.9;  // not read for BLEND
  const std::string path = Write("blend.gltf", testing::AlphaCardGltf(blend));
  absl::StatusOr<MeshFileData> mesh = LoadMeshFile(path, "scene.json: meshes[0].path");
  ASSERT_TRUE(mesh.ok()) << mesh.status();
  ASSERT_EQ(mesh->masks.size(), 1u);
  EXPECT_EQ(mesh->masks[0]->cutoff, 0.5f);
  ASSERT_EQ(mesh->warnings.size(), 1u);
  EXPECT_THAT(mesh->warnings[0], HasSubstr("scene.json: meshes[0].path"));
  EXPECT_THAT(mesh->warnings[0], HasSubstr("\"card\""));
  EXPECT_THAT(mesh->warnings[0], HasSubstr("BLEND: baked as MASK at alphaCutoff 0.5"));
}

TEST_F(MeshFileTest, ExternalTextureIsReadNextToTheFileAndMissingOneIsNamed) {
  testing::AlphaCardOptions external;
  external.texture_uri = "leaf.png";
  const std::string path = Write("card.gltf", testing::AlphaCardGltf(external));
  absl::StatusOr<MeshFileData> mesh = LoadMeshFile(path, "ctx");
  ASSERT_EQ(mesh.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(mesh.status().message(), HasSubstr(absl::StrCat("cannot read \"", path, "\"")));
  EXPECT_THAT(mesh.status().message(), HasSubstr("material \"card\": texture \"leaf.png\""));

  Write("leaf.png", testing::AlphaCardPng());
  mesh = LoadMeshFile(path, "ctx");
  ASSERT_TRUE(mesh.ok()) << mesh.status();
  absl::StatusOr<MeshFileData> embedded =
      LoadMeshFile(Write("embedded.gltf", testing::AlphaCardGltf()), "ctx");
  ASSERT_TRUE(embedded.ok()) << embedded.status();
  ASSERT_EQ(mesh->masks.size(), 1u);
  EXPECT_TRUE(SameMask(*mesh->masks[0], *embedded->masks[0]));

  Write("leaf.png", "\xff\xd8\xff\xe0 a JPEG, say");
  mesh = LoadMeshFile(path, "ctx");
  ASSERT_EQ(mesh.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(mesh.status().message(), HasSubstr("not a readable PNG"));
}

TEST_F(MeshFileTest, AlphaTestedMeshWithoutTexcoordsIsAnError) {
  testing::AlphaCardOptions bare;
  bare.texcoords = false;
  absl::StatusOr<MeshFileData> mesh =
      LoadMeshFile(Write("bare.gltf", testing::AlphaCardGltf(bare)), "ctx");
  ASSERT_EQ(mesh.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(mesh.status().message(), HasSubstr("has no texture coordinates"));
}

TEST_F(MeshFileTest, ObjMapDIsTestedAtOneHalfOnItsGrayWithObjUvsFlipped) {
  // map_d without alpha: its gray is the coverage. 2 x 2, gray 255 on the image's top row, 0 on
  // the bottom row; OBJ's vt (0, 0) is the image's bottom-left.
  absl::StatusOr<std::string> png = EncodeRgbPng(2, 2,
                                                 {255, 255, 255, 255, 255, 255,  //
                                                  0, 0, 0, 0, 0, 0});
  ASSERT_TRUE(png.ok()) << png.status();
  Write("cut.png", *png);
  Write("card.mtl", "newmtl card\nmap_d cut.png\n");
  const std::string path = Write("card.obj",
                                 "mtllib card.mtl\n"
                                 "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                                 "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
                                 "usemtl card\n"
                                 "f 1/1 2/2 3/3 4/4\n");
  absl::StatusOr<MeshFileData> mesh = LoadMeshFile(path, "ctx");
  ASSERT_TRUE(mesh.ok()) << mesh.status();
  ASSERT_EQ(mesh->masks.size(), 1u);
  EXPECT_EQ(mesh->masks[0]->cutoff, 0.5f);
  // vt v = 1 (y = 1) is the image's top: our v = 0.
  for (size_t v = 0; v < mesh->positions.size(); ++v) {
    const glm::dvec3& p = mesh->positions[v];
    EXPECT_EQ(mesh->uvs[v], glm::vec2(p.x, 1 - p.y)) << "vertex " << v;
  }
  // So the quad's upper half (its top row's texels) casts and the lower half does not.
  EXPECT_TRUE(mesh->masks[0]->CastsAt({0.5, 1 - 0.75}));
  EXPECT_FALSE(mesh->masks[0]->CastsAt({0.5, 1 - 0.25}));
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
