#include "core/scene/scene_loader.h"

#include <unistd.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <memory>
#include <numbers>
#include <string>
#include <tuple>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "core/assets/asset_store.h"
#include "core/assets/mesh_asset.h"
#include "core/scene/mesh_file.h"
#include "tests/test_support.h"

namespace pdsm {
namespace {

using ::testing::HasSubstr;

// A unit square at y = 0 as an inline mesh, and a rect light above it.
constexpr char kSquare[] =
    R"({"inline": {"positions": [0,0,0, 1,0,0, 1,0,1, 0,0,1], "indices": [0,1,2, 0,2,3]}})";
constexpr char kRect[] =
    R"({"rect": {"center": [0,10,0], "normal": [0,-1,0], "up": [0,0,1], "size": [3,2]}})";

std::string SceneJson(const std::string& meshes = kSquare, const std::string& light = kRect,
                      const std::string& bake = "{}") {
  return absl::StrCat(R"({"name": "test", "meshes": [)", meshes, R"(], "light": )", light,
                      R"(, "bake": )", bake, "}");
}

constexpr char kPlyQuad[] =
    "ply\nformat ascii 1.0\nelement vertex 4\n"
    "property float x\nproperty float y\nproperty float z\n"
    "element face 2\nproperty list uchar int vertex_indices\nend_header\n"
    "0 1 0\n1 1 0\n1 1 1\n0 1 1\n3 0 1 2\n3 0 2 3\n";

class SceneLoaderTest : public ::testing::Test {
 protected:
  // Writes `contents` to dir_/relative_path (folders created) and returns the full path.
  std::string Write(const std::string& relative_path, const std::string& contents) {
    const std::filesystem::path path = dir_ / relative_path;
    std::filesystem::create_directories(path.parent_path());
    std::ofstream(path, std::ios::binary) << contents;
    return path.string();
  }

  absl::StatusOr<Scene> Load(const std::string& json, const pdsm::v1::BakeParams& overrides = {}) {
    scene_path_ = Write("scene.json", json);
    return LoadSceneFile(scene_path_, overrides);
  }

  // The error contract: INVALID_ARGUMENT, "SCENE_PATH: FIELD: ...".
  void ExpectInvalid(const absl::StatusOr<Scene>& scene, const std::string& field,
                     const std::string& detail = "") {
    ASSERT_FALSE(scene.ok()) << "expected an error naming " << field;
    EXPECT_EQ(scene.status().code(), absl::StatusCode::kInvalidArgument) << scene.status();
    EXPECT_THAT(scene.status().message(), HasSubstr(absl::StrCat(scene_path_, ": ", field, ":")));
    if (!detail.empty()) {
      EXPECT_THAT(scene.status().message(), HasSubstr(detail));
    }
  }

  ::pdsm::testing::TempDir temp_dir_;  // a fresh folder per test, removed after it
  const std::filesystem::path dir_ = temp_dir_.path();
  std::string scene_path_;
};

// ---- Rejected input --------------------------------------------------------------------

struct BadCase {
  const char* name;
  std::string meshes;
  std::string light;
  std::string bake;
  std::string field;   // the field the message must name
  std::string detail;  // and a piece of the "what (got VALUE)"
};

class SceneLoaderBadInputTest : public SceneLoaderTest,
                                public ::testing::WithParamInterface<BadCase> {};

TEST_P(SceneLoaderBadInputTest, IsInvalidArgumentNamingFileAndField) {
  const BadCase& c = GetParam();
  ExpectInvalid(Load(SceneJson(c.meshes, c.light, c.bake)), c.field, c.detail);
}

std::string InlineMesh(const std::string& positions, const std::string& indices,
                       const std::string& extra = "") {
  return absl::StrCat(R"({"inline": {"positions": [)", positions, R"(], "indices": [)", indices,
                      "]}", extra, "}");
}
const std::string kTri = "0,0,0, 1,0,0, 0,0,1";
std::string WithTransform(const std::string& transform) {
  return InlineMesh(kTri, "0,1,2", absl::StrCat(R"(, "transform": [)", transform, "]"));
}
std::string Rect(const std::string& center, const std::string& normal, const std::string& up,
                 const std::string& size) {
  return absl::StrCat(R"({"rect": {"center": [)", center, R"(], "normal": [)", normal,
                      R"(], "up": [)", up, R"(], "size": [)", size, "]}}");
}
std::string Sun(const std::string& degrees) {
  return absl::StrCat(R"({"sun": {"direction": [0,-1,0], "angularDiameterDeg": )", degrees, "}}");
}

// Prefixed "SceneLoader" so that --gtest_filter='Scene*' selects these too.
INSTANTIATE_TEST_SUITE_P(
    SceneLoader, SceneLoaderBadInputTest,
    ::testing::Values(
        BadCase{"NanPosition", InlineMesh(R"(0,"NaN",0, 1,0,0, 0,0,1)", "0,1,2"), kRect, "{}",
                "meshes[0].inline.positions[1]", "must be finite (got NaN)"},
        BadCase{"InfinityPosition", InlineMesh(R"(0,0,0, 1,"Infinity",0, 0,0,1)", "0,1,2"), kRect,
                "{}", "meshes[0].inline.positions[4]", "(got Infinity)"},
        BadCase{"NanTransform", WithTransform(R"(1,0,0,"NaN", 0,1,0,0, 0,0,1,0, 0,0,0,1)"), kRect,
                "{}", "meshes[0].transform[3]", "(got NaN)"},
        BadCase{"InfinityTransform",
                WithTransform(R"(1,0,0,0, 0,"-Infinity",0,0, 0,0,1,0, 0,0,0,1)"), kRect, "{}",
                "meshes[0].transform[5]", "(got -Infinity)"},
        BadCase{"NanLightCenter", kSquare, Rect(R"("NaN",10,0)", "0,-1,0", "0,0,1", "1,1"), "{}",
                "light.rect.center[0]", "(got NaN)"},
        BadCase{"InfinityLightCenter", kSquare, Rect(R"(0,"Infinity",0)", "0,-1,0", "0,0,1", "1,1"),
                "{}", "light.rect.center[1]", "(got Infinity)"},
        BadCase{"ZeroRectWidth", kSquare, Rect("0,10,0", "0,-1,0", "0,0,1", "0,1"), "{}",
                "light.rect.size[0]", "must be > 0 (got 0)"},
        BadCase{"NegativeRectHeight", kSquare, Rect("0,10,0", "0,-1,0", "0,0,1", "1,-2"), "{}",
                "light.rect.size[1]", "(got -2)"},
        BadCase{"RectSizeCount", kSquare, Rect("0,10,0", "0,-1,0", "0,0,1", "1"), "{}",
                "light.rect.size", "(got 1)"},
        BadCase{"ZeroNormal", kSquare, Rect("0,10,0", "0,0,0", "0,0,1", "1,1"), "{}",
                "light.rect.normal", "must be non-zero"},
        BadCase{"UpParallelToNormal", kSquare, Rect("0,10,0", "0,-1,0", "0,3,0", "1,1"), "{}",
                "light.rect.up", "parallel"},
        BadCase{"MissingUp", kSquare,
                R"({"rect": {"center": [0,10,0], "normal": [0,-1,0], "size": [1,1]}})", "{}",
                "light.rect.up", "must have 3 numbers (got 0)"},
        BadCase{"DiskRadiusZero", kSquare,
                R"({"disk": {"center": [0,10,0], "normal": [0,-1,0], "radius": 0}})", "{}",
                "light.disk.radius", "must be > 0 (got 0)"},
        BadCase{"SunAngleZero", kSquare, Sun("0"), "{}", "light.sun.angularDiameterDeg", "(got 0)"},
        BadCase{"SunAngleNinety", kSquare, Sun("90"), "{}", "light.sun.angularDiameterDeg",
                "must be in (0, 90) degrees (got 90)"},
        BadCase{"NoLight", kSquare, "{}", "{}", "light",
                "one of rect, disk, spot, sphere, sun is required"},
        BadCase{"SamplesZero", kSquare, kRect, R"({"samples": 0})", "bake.samples",
                "must be in [1, 65536] (got 0)"},
        BadCase{"SamplesTooMany", kSquare, kRect, R"({"samples": 65537})", "bake.samples",
                "(got 65537)"},
        BadCase{"ResolutionZero", kSquare, kRect, R"({"resolution": [0, 10]})",
                "bake.resolution[0]", "must be in [1, 65536] (got 0)"},
        BadCase{"ResolutionTooLarge", kSquare, kRect, R"({"resolution": [65537, 10]})",
                "bake.resolution[0]", "(got 65537)"},
        BadCase{"ResolutionTooManyPixels", kSquare, kRect, R"({"resolution": [32768, 32769]})",
                "bake.resolution", "at most 1073741824 pixels (32768x32768) (got 32768x32769)"},
        BadCase{"ResolutionTooManyTiles", kSquare, kRect,
                R"({"resolution": [8192, 8192], "tileSize": 7})", "bake.tileSize",
                "a 8192x8192 map in tiles of 7 pixels has 1371241 tiles, more than 1048576"},
        BadCase{"ResolutionCount", kSquare, kRect, R"({"resolution": [1]})", "bake.resolution",
                "must have 2 numbers [width, height] (got 1)"},
        BadCase{"ShadowMapResolutionZero", kSquare, kRect, R"({"shadowMapResolution": 0})",
                "bake.shadowMapResolution", "(got 0)"},
        BadCase{"EpsilonNegative", kSquare, kRect, R"({"epsilon": -0.1})", "bake.epsilon",
                "must be in [0, 1] (got -0.1)"},
        BadCase{"EpsilonAboveOne", kSquare, kRect, R"({"epsilon": 1.5})", "bake.epsilon",
                "(got 1.5)"},
        BadCase{"EpsilonNan", kSquare, kRect, R"({"epsilon": "NaN"})", "bake.epsilon", "(got NaN)"},
        BadCase{"TileSizeZero", kSquare, kRect, R"({"tileSize": 0})", "bake.tileSize", "(got 0)"},
        BadCase{"DepthBiasNegative", kSquare, kRect, R"({"depthBias": -1})", "bake.depthBias",
                "must be >= 0 (got -1)"},
        BadCase{"SlopeBiasInfinite", kSquare, kRect, R"({"slopeBias": "Infinity"})",
                "bake.slopeBias", "(got Infinity)"},
        BadCase{"UnknownSamplingNumber", kSquare, kRect, R"({"sampling": 7})", "bake.sampling",
                "unknown value (got 7)"},
        BadCase{"FrustumWindowEmpty", kSquare, kRect,
                R"({"frustum": {"window": [1,-1,-1,1], "depthRange": [1,2]}})",
                "bake.frustum.window", "sMin < sMax"},
        BadCase{"FrustumWindowCount", kSquare, kRect,
                R"({"frustum": {"window": [1,2,3], "depthRange": [1,2]}})", "bake.frustum.window",
                "(got 3)"},
        BadCase{"FrustumNearZeroForRect", kSquare, kRect,
                R"({"frustum": {"window": [-1,1,-1,1], "depthRange": [0,2]}})",
                "bake.frustum.depthRange", "0 < near < far"},
        BadCase{"FrustumFarBeforeNear", kSquare, Sun("1"),
                R"({"frustum": {"window": [-1,1,-1,1], "depthRange": [3,2]}})",
                "bake.frustum.depthRange", "near < far"},
        BadCase{"IndexOutOfRange", InlineMesh(kTri, "0,1,3"), kRect, "{}",
                "meshes[0].inline.indices[2]", "must be < 3, the vertex count (got 3)"},
        BadCase{"PositionsNotTriples", InlineMesh("0,0,0, 1,0,0, 0,0", "0,1,2"), kRect, "{}",
                "meshes[0].inline.positions", "multiple of 3 (got 8)"},
        BadCase{"IndicesNotTriples", InlineMesh(kTri, "0,1"), kRect, "{}",
                "meshes[0].inline.indices", "multiple of 3 (got 2)"},
        BadCase{"NoIndices", InlineMesh(kTri, ""), kRect, "{}", "meshes[0].inline.indices",
                "no triangles"},
        BadCase{"TransformFifteenNumbers", WithTransform("1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0"), kRect,
                "{}", "meshes[0].transform", "must have 0 or 16 numbers (got 15)"},
        BadCase{"SingularTransform", WithTransform("1,0,0,0, 0,0,0,0, 0,0,1,0, 0,0,0,1"), kRect,
                "{}", "meshes[0].transform", "invertible"},
        BadCase{"NearlySingularTransform",
                WithTransform("1e6,0,0,0, 1e6,1e-9,0,0, 0,0,1,0, 0,0,0,1"), kRect, "{}",
                "meshes[0].transform", "invertible"},
        BadCase{"ColumnMajorTransform", WithTransform("1,0,0,0, 0,1,0,0, 0,0,1,0, 5,6,7,1"), kRect,
                "{}", "meshes[0].transform", "translation in elements 3, 7, 11"},
        BadCase{"MeshWithoutSource", R"({"role": "CASTER_ONLY"})", kRect, "{}", "meshes[0]",
                "one of path, inline, assetSha256 is required"},
        BadCase{"SecondMeshBad", absl::StrCat(kSquare, ", ", InlineMesh(kTri, "0,1,5")), kRect,
                "{}", "meshes[1].inline.indices[2]", "(got 5)"}),
    [](const ::testing::TestParamInfo<BadCase>& info) { return info.param.name; });

TEST_F(SceneLoaderTest, MalformedJson) {
  absl::StatusOr<Scene> scene = Load(R"({"name": "x", "meshes": [})");
  ASSERT_EQ(scene.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(scene.status().message(),
              HasSubstr(absl::StrCat(scene_path_, ": invalid scene JSON: ")));
}

TEST_F(SceneLoaderTest, EmptyFileIsMalformedJson) {
  absl::StatusOr<Scene> scene = Load("");
  ASSERT_EQ(scene.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(scene.status().message(),
              HasSubstr(absl::StrCat(scene_path_, ": invalid scene JSON: ")));
}

TEST_F(SceneLoaderTest, UnknownFieldIsNamed) {
  absl::StatusOr<Scene> scene = Load(R"({"meshs": [], "light": )" + std::string(kRect) + "}");
  ASSERT_EQ(scene.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(scene.status().message(),
              HasSubstr(absl::StrCat(scene_path_, ": invalid scene JSON: ")));
  EXPECT_THAT(scene.status().message(), HasSubstr("meshs"));
}

TEST_F(SceneLoaderTest, NestedUnknownFieldIsNamed) {
  absl::StatusOr<Scene> scene = Load(SceneJson(kSquare, kRect, R"({"sample": 4})"));
  ASSERT_EQ(scene.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(scene.status().message(), HasSubstr(scene_path_));
  EXPECT_THAT(scene.status().message(), HasSubstr("sample"));
}

TEST_F(SceneLoaderTest, TwoLightShapesIsAnError) {
  // A oneof set twice: protobuf's parser refuses it and names the oneof.
  absl::StatusOr<Scene> scene = Load(
      SceneJson(kSquare,
                R"({"rect": {"center": [0,10,0], "normal": [0,-1,0], "up": [0,0,1], "size": [1,1]},
          "disk": {"center": [0,10,0], "normal": [0,-1,0], "radius": 1}})"));
  ASSERT_EQ(scene.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(scene.status().message(),
              HasSubstr(absl::StrCat(scene_path_, ": invalid scene JSON: ")));
  EXPECT_THAT(scene.status().message(), HasSubstr("light"));
  EXPECT_THAT(scene.status().message(), HasSubstr("shape"));
}

TEST_F(SceneLoaderTest, PathAndInlineTogetherIsAnError) {
  absl::StatusOr<Scene> scene =
      Load(SceneJson(R"({"path": "a.ply", "inline": {"positions": [0,0,0], "indices": []}})"));
  ASSERT_EQ(scene.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(scene.status().message(), HasSubstr("meshes[0]"));
  EXPECT_THAT(scene.status().message(), HasSubstr("source"));
}

TEST_F(SceneLoaderTest, NegativeSamplesIsAParseError) {
  absl::StatusOr<Scene> scene = Load(SceneJson(kSquare, kRect, R"({"samples": -4})"));
  ASSERT_EQ(scene.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(scene.status().message(), HasSubstr(scene_path_));
  EXPECT_THAT(scene.status().message(), HasSubstr("bake.samples"));
}

TEST_F(SceneLoaderTest, MissingSceneFileIsNotFound) {
  const std::string path = (dir_ / "absent.json").string();
  absl::StatusOr<Scene> scene = LoadSceneFile(path);
  ASSERT_EQ(scene.status().code(), absl::StatusCode::kNotFound);
  EXPECT_THAT(scene.status().message(), HasSubstr(path));
}

TEST_F(SceneLoaderTest, MissingMeshFileNamesFieldAndFile) {
  absl::StatusOr<Scene> scene = Load(SceneJson(R"({"path": "models/missing.ply"})"));
  ExpectInvalid(scene, "meshes[0].path", "models/missing.ply");
  EXPECT_THAT(scene.status().message(), HasSubstr("no such file"));
}

TEST_F(SceneLoaderTest, UnreadableMeshFileNamesFieldAndFile) {
  std::string garbage;
  for (int i = 0; i < 300; ++i) garbage.push_back(static_cast<char>((i * 131 + 7) & 0xff));
  Write("models/garbage.ply", garbage);
  absl::StatusOr<Scene> scene =
      Load(SceneJson(absl::StrCat(kSquare, R"(, {"path": "models/garbage.ply"})")));
  ExpectInvalid(scene, "meshes[1].path", "cannot read");
  EXPECT_THAT(scene.status().message(), HasSubstr("models/garbage.ply"));
}

TEST_F(SceneLoaderTest, OverrideErrorsSayTheValueCameFromTheOverrides) {
  pdsm::v1::BakeParams overrides;
  overrides.set_samples(0);
  ExpectInvalid(Load(SceneJson(kSquare, kRect, R"({"samples": 16})"), overrides),
                "bake.samples (override)", "(got 0)");
}

TEST_F(SceneLoaderTest, ProtoWithoutBaseDirRefusesMeshFiles) {
  pdsm::v1::Scene message;
  message.add_meshes()->set_path("models/thing.ply");
  auto* rect = message.mutable_light()->mutable_rect();
  for (double x : {0.0, 10.0, 0.0}) rect->add_center(x);
  for (double x : {0.0, -1.0, 0.0}) rect->add_normal(x);
  for (double x : {0.0, 0.0, 1.0}) rect->add_up(x);
  for (double x : {1.0, 1.0}) rect->add_size(x);
  absl::StatusOr<Scene> scene = SceneFromProto(message, "job 42", "");
  ASSERT_EQ(scene.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(scene.status().message(),
              HasSubstr("job 42: meshes[0].path: mesh files are not accepted here; send "
                        "inline geometry"));

  // The same message with inline geometry is fine.
  auto* mesh = message.mutable_meshes(0)->mutable_inline_();
  for (double x : {0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0}) mesh->add_positions(x);
  for (uint32_t i : {0u, 1u, 2u}) mesh->add_indices(i);
  scene = SceneFromProto(message, "job 42", "");
  ASSERT_TRUE(scene.ok()) << scene.status();
  EXPECT_EQ(scene->source_path, "job 42");
  EXPECT_EQ(scene->meshes[0].label, "meshes[0] (inline)");
}

// A name is a label: 256 bytes at most (a 5 MiB one made a job listing outgrow 4 MiB).
TEST_F(SceneLoaderTest, SceneNameIsAtMost256Bytes) {
  pdsm::v1::Scene message;
  auto* rect = message.mutable_light()->mutable_rect();
  for (double x : {0.0, 10.0, 0.0}) rect->add_center(x);
  for (double x : {0.0, -1.0, 0.0}) rect->add_normal(x);
  for (double x : {0.0, 0.0, 1.0}) rect->add_up(x);
  for (double x : {1.0, 1.0}) rect->add_size(x);
  auto* mesh = message.add_meshes()->mutable_inline_();
  for (double x : {0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0}) mesh->add_positions(x);
  for (uint32_t i : {0u, 1u, 2u}) mesh->add_indices(i);
  message.set_name(std::string(256, 'n'));
  EXPECT_TRUE(SceneFromProto(message, "job 42", "").ok());
  message.set_name(std::string(257, 'n'));
  const absl::Status s = SceneFromProto(message, "job 42", "").status();
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(s.message(), HasSubstr("job 42: name: at most 256 bytes (got 257)"));
}

// ---- Accepted input --------------------------------------------------------------------

TEST_F(SceneLoaderTest, DesignExampleLoads) {
  Write("models/thing.ply", kPlyQuad);
  absl::StatusOr<Scene> scene = Load(R"({
    "name": "plates",
    "meshes": [
      {"path": "models/thing.ply", "transform": [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1],
       "role": "CASTER_AND_RECEIVER"},
      {"inline": {"positions": [-10,0,-10, 10,0,-10, 10,0,10, -10,0,10],
                  "indices": [0,1,2, 0,2,3]}, "role": "RECEIVER_ONLY"}
    ],
    "light": {"rect": {"center": [0,10,0], "normal": [0,-1,0], "up": [0,0,1], "size": [3,3]}},
    "bake": {"resolution": [512,512], "samples": 256, "shadowMapResolution": 512,
             "epsilon": 0.02}
  })");
  ASSERT_TRUE(scene.ok()) << scene.status();
  EXPECT_EQ(scene->name, "plates");
  EXPECT_EQ(scene->source_path, scene_path_);
  ASSERT_EQ(scene->meshes.size(), 2u);
  EXPECT_EQ(scene->meshes[0].label, "meshes[0] (models/thing.ply)");
  EXPECT_EQ(scene->meshes[0].role, MeshRole::kCasterAndReceiver);
  EXPECT_EQ(scene->meshes[0].indices.size(), 6u);
  for (const glm::dvec3& p : scene->meshes[0].positions_world) EXPECT_EQ(p.y, 1.0);
  EXPECT_EQ(scene->meshes[1].label, "meshes[1] (inline)");
  EXPECT_EQ(scene->meshes[1].role, MeshRole::kReceiverOnly);
  EXPECT_EQ(scene->meshes[1].positions_world[2], glm::dvec3(10, 0, 10));
  EXPECT_EQ(scene->meshes[1].indices, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3}));

  EXPECT_EQ(scene->light.shape, LightShape::kRect);
  EXPECT_EQ(scene->light.frame.center, glm::dvec3(0, 10, 0));
  EXPECT_EQ(scene->light.frame.n, glm::dvec3(0, -1, 0));
  EXPECT_EQ(scene->light.half_width, 1.5);
  EXPECT_EQ(scene->light.half_height, 1.5);

  EXPECT_EQ(scene->bake.width, 512);
  EXPECT_EQ(scene->bake.height, 512);
  EXPECT_EQ(scene->bake.samples, 256);
  EXPECT_EQ(scene->bake.shadow_map_resolution, 512);
  EXPECT_EQ(scene->bake.epsilon, 0.02);
}

TEST_F(SceneLoaderTest, DefaultsAreFilled) {
  absl::StatusOr<Scene> scene = Load(SceneJson());
  ASSERT_TRUE(scene.ok()) << scene.status();
  const BakeSettings defaults;
  EXPECT_EQ(scene->bake.width, defaults.width);
  EXPECT_EQ(scene->bake.height, defaults.height);
  EXPECT_EQ(scene->bake.samples, defaults.samples);
  EXPECT_EQ(scene->bake.shadow_map_resolution, defaults.shadow_map_resolution);
  EXPECT_EQ(scene->bake.epsilon, defaults.epsilon);
  EXPECT_FALSE(scene->bake.depth_bias.has_value());
  EXPECT_EQ(scene->bake.slope_bias, defaults.slope_bias);
  EXPECT_EQ(scene->bake.tile_size, defaults.tile_size);
  EXPECT_EQ(scene->bake.seed, defaults.seed);
  EXPECT_EQ(scene->bake.sampling, SamplingPattern::kSobol);
  EXPECT_EQ(scene->bake.compression_metric, CompressionMetric::kVertical);
  EXPECT_FALSE(scene->bake.frustum.has_value());
  EXPECT_EQ(scene->meshes[0].role, MeshRole::kCasterAndReceiver);
}

TEST_F(SceneLoaderTest, AllBakeFieldsAreRead) {
  absl::StatusOr<Scene> scene = Load(SceneJson(kSquare, kRect, R"({
      "resolution": [300, 200], "samples": 9, "shadowMapResolution": 700, "epsilon": 0,
      "depthBias": 0.25, "slopeBias": 0, "tileSize": 32, "seed": "12345678901",
      "sampling": "UNIFORM", "compressionMetric": "PERPENDICULAR",
      "frustum": {"window": [-0.5, 0.5, -0.25, 0.75], "depthRange": [1, 20]}})"));
  ASSERT_TRUE(scene.ok()) << scene.status();
  EXPECT_EQ(scene->bake.width, 300);
  EXPECT_EQ(scene->bake.height, 200);
  EXPECT_EQ(scene->bake.samples, 9);
  EXPECT_EQ(scene->bake.shadow_map_resolution, 700);
  EXPECT_EQ(scene->bake.epsilon, 0);
  EXPECT_EQ(scene->bake.depth_bias, 0.25);
  EXPECT_EQ(scene->bake.slope_bias, 0);
  EXPECT_EQ(scene->bake.tile_size, 32);
  EXPECT_EQ(scene->bake.seed, 12345678901u);
  EXPECT_EQ(scene->bake.sampling, SamplingPattern::kUniform);
  EXPECT_EQ(scene->bake.compression_metric, CompressionMetric::kPerpendicular);
  ASSERT_TRUE(scene->bake.frustum.has_value());
  EXPECT_EQ(scene->bake.frustum->s_min, -0.5);
  EXPECT_EQ(scene->bake.frustum->s_max, 0.5);
  EXPECT_EQ(scene->bake.frustum->t_min, -0.25);
  EXPECT_EQ(scene->bake.frustum->t_max, 0.75);
  EXPECT_EQ(scene->bake.frustum->z_near, 1);
  EXPECT_EQ(scene->bake.frustum->z_far, 20);
}

TEST_F(SceneLoaderTest, LimitsAreInclusive) {
  absl::StatusOr<Scene> scene = Load(SceneJson(kSquare, kRect, R"({
      "resolution": [65536, 1], "samples": 65536, "shadowMapResolution": 16384,
      "epsilon": 1, "tileSize": 4096})"));
  ASSERT_TRUE(scene.ok()) << scene.status();
  EXPECT_EQ(scene->bake.samples, kMaxSamples);
  EXPECT_EQ(scene->bake.width, kMaxPdsmResolution);
  // 2^30 pixels in 2^20 tiles: both limits at once.
  scene = Load(SceneJson(kSquare, kRect, R"({"resolution": [32768, 32768], "tileSize": 32})"));
  ASSERT_TRUE(scene.ok()) << scene.status();
  EXPECT_EQ(int64_t{scene->bake.width} * scene->bake.height, kMaxPdsmPixels);
}

TEST_F(SceneLoaderTest, SamplingPatternsAndAdaptiveAreRead) {
  for (auto [name, pattern] :
       {std::pair{"SOBOL", SamplingPattern::kSobol}, std::pair{"HALTON", SamplingPattern::kHalton},
        std::pair{"BLUE_NOISE", SamplingPattern::kBlueNoise}}) {
    absl::StatusOr<Scene> scene =
        Load(SceneJson(kSquare, kRect,
                       absl::StrCat(R"({"samples": 128, "sampling": ")", name,
                                    R"(", "adaptiveTolerance": 0.03, "adaptiveMinSamples": 8})")));
    ASSERT_TRUE(scene.ok()) << scene.status();
    EXPECT_EQ(scene->bake.sampling, pattern);
    EXPECT_TRUE(scene->bake.adaptive());
    EXPECT_EQ(scene->bake.adaptive_tolerance, 0.03);
    EXPECT_EQ(scene->bake.adaptive_min_samples, 8);
  }
  // Adaptive without a pattern: Sobol; the first batch is capped at the samples.
  absl::StatusOr<Scene> scene =
      Load(SceneJson(kSquare, kRect, R"({"samples": 4, "adaptiveTolerance": 0.1})"));
  ASSERT_TRUE(scene.ok()) << scene.status();
  EXPECT_EQ(scene->bake.sampling, SamplingPattern::kSobol);
  EXPECT_EQ(scene->bake.adaptive_min_samples, 4);
  // Tolerance 0 is "off".
  scene = Load(SceneJson(kSquare, kRect, R"({"adaptiveTolerance": 0})"));
  ASSERT_TRUE(scene.ok()) << scene.status();
  EXPECT_FALSE(scene->bake.adaptive());
  EXPECT_EQ(scene->bake.sampling, SamplingPattern::kSobol);
  // STRATIFIED stays available to fixed-count bakes.
  scene = Load(SceneJson(kSquare, kRect, R"({"sampling": "STRATIFIED"})"));
  ASSERT_TRUE(scene.ok()) << scene.status();
  EXPECT_EQ(scene->bake.sampling, SamplingPattern::kStratified);
}

TEST_F(SceneLoaderTest, BadAdaptiveSettingsNameTheField) {
  for (auto [bake, field] :
       {std::pair{R"({"adaptiveTolerance": -0.1})", "bake.adaptiveTolerance"},
        std::pair{R"({"adaptiveTolerance": 1.5})", "bake.adaptiveTolerance"},
        std::pair{R"({"adaptiveMinSamples": 0})", "bake.adaptiveMinSamples"},
        std::pair{R"({"adaptiveTolerance": 0.1, "sampling": "STRATIFIED"})", "bake.sampling"}}) {
    absl::StatusOr<Scene> scene = Load(SceneJson(kSquare, kRect, bake));
    ASSERT_FALSE(scene.ok()) << bake;
    EXPECT_EQ(scene.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_NE(scene.status().message().find(field), std::string::npos) << scene.status();
  }
}

// What a job reports as its settings: every default filled in, so that loading the scene with
// them as overrides gives the same settings whatever the loader's defaults.
TEST_F(SceneLoaderTest, EffectiveBakeParamsRoundTrip) {
  for (const std::string& bake :
       {std::string("{}"),
        std::string(R"({"resolution": [300, 200], "samples": 9, "depthBias": 0.25, "seed": "77",
            "sampling": "HALTON", "compressionMetric": "PERPENDICULAR", "surfacesOnly": true,
            "frustum": {"window": [-0.5, 0.5, -0.25, 0.75], "depthRange": [1, 20]}})"),
        std::string(R"({"samples": 64, "adaptiveTolerance": 0.05, "tileGroupSize": 2})")}) {
    absl::StatusOr<Scene> scene = Load(SceneJson(kSquare, kRect, bake));
    ASSERT_TRUE(scene.ok()) << scene.status();
    absl::StatusOr<pdsm::v1::Scene> message =
        ParseSceneFile(Write("effective.json", SceneJson(kSquare, kRect, bake)));
    ASSERT_TRUE(message.ok());
    absl::StatusOr<pdsm::v1::BakeParams> effective =
        EffectiveBakeParams(message->bake(), /*sun=*/false, "job 1");
    ASSERT_TRUE(effective.ok()) << effective.status();
    // Every field is set (depthBias only when given: the plan derives it otherwise).
    EXPECT_TRUE(effective->has_samples() && effective->has_seed() && effective->has_epsilon());
    EXPECT_NE(effective->sampling(), pdsm::v1::SAMPLING_DEFAULT);
    EXPECT_EQ(effective->has_depth_bias(), scene->bake.depth_bias.has_value());
    // Loading an empty bake block with them as overrides gives the same settings.
    absl::StatusOr<Scene> again = Load(SceneJson(kSquare, kRect, "{}"), *effective);
    ASSERT_TRUE(again.ok()) << again.status();
    const BakeSettings& x = scene->bake;
    const BakeSettings& y = again->bake;
    EXPECT_EQ(
        std::tie(x.width, x.height, x.samples, x.shadow_map_resolution, x.epsilon, x.depth_bias,
                 x.slope_bias, x.tile_size, x.seed, x.sampling, x.compression_metric,
                 x.adaptive_tolerance, x.adaptive_min_samples, x.surfaces_only, x.tile_group_size),
        std::tie(y.width, y.height, y.samples, y.shadow_map_resolution, y.epsilon, y.depth_bias,
                 y.slope_bias, y.tile_size, y.seed, y.sampling, y.compression_metric,
                 y.adaptive_tolerance, y.adaptive_min_samples, y.surfaces_only, y.tile_group_size))
        << bake;
    EXPECT_EQ(x.frustum.has_value(), y.frustum.has_value());
  }
  pdsm::v1::BakeParams bad;
  bad.set_samples(0);
  absl::StatusOr<pdsm::v1::BakeParams> refused = EffectiveBakeParams(bad, false, "job 7");
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.status().message().find("job 7: bake.samples"), std::string::npos)
      << refused.status();
}

TEST_F(SceneLoaderTest, OverridesReplaceSetFieldsOnly) {
  pdsm::v1::BakeParams overrides;
  overrides.add_resolution(100);
  overrides.add_resolution(50);
  overrides.set_samples(16);
  overrides.set_epsilon(0);  // set to the zero value: still an override
  overrides.set_sampling(pdsm::v1::UNIFORM);
  overrides.mutable_frustum()->add_window(-1);
  overrides.mutable_frustum()->add_window(1);
  overrides.mutable_frustum()->add_window(-2);
  overrides.mutable_frustum()->add_window(2);
  overrides.mutable_frustum()->add_depth_range(0.5);
  overrides.mutable_frustum()->add_depth_range(30);
  absl::StatusOr<Scene> scene =
      Load(SceneJson(kSquare, kRect,
                     R"({"resolution": [512, 256], "samples": 256, "epsilon": 0.02, "tileSize": 16,
                    "shadowMapResolution": 1024,
                    "frustum": {"window": [-9, 9, -9, 9], "depthRange": [1, 2]}})"),
           overrides);
  ASSERT_TRUE(scene.ok()) << scene.status();
  EXPECT_EQ(scene->bake.width, 100);
  EXPECT_EQ(scene->bake.height, 50);
  EXPECT_EQ(scene->bake.samples, 16);
  EXPECT_EQ(scene->bake.epsilon, 0);
  EXPECT_EQ(scene->bake.sampling, SamplingPattern::kUniform);
  ASSERT_TRUE(scene->bake.frustum.has_value());
  EXPECT_EQ(scene->bake.frustum->s_min, -1);
  EXPECT_EQ(scene->bake.frustum->t_max, 2);
  EXPECT_EQ(scene->bake.frustum->z_far, 30);
  // Not overridden: the file's values stay.
  EXPECT_EQ(scene->bake.tile_size, 16);
  EXPECT_EQ(scene->bake.shadow_map_resolution, 1024);
}

TEST_F(SceneLoaderTest, RolesAreMapped) {
  absl::StatusOr<Scene> scene =
      Load(SceneJson(absl::StrCat(InlineMesh(kTri, "0,1,2", R"(, "role": "CASTER_ONLY")"), ", ",
                                  InlineMesh(kTri, "0,1,2", R"(, "role": "RECEIVER_ONLY")"), ", ",
                                  InlineMesh(kTri, "0,1,2", R"(, "role": "CASTER_AND_RECEIVER")"),
                                  ", ", InlineMesh(kTri, "0,1,2"))));
  ASSERT_TRUE(scene.ok()) << scene.status();
  ASSERT_EQ(scene->meshes.size(), 4u);
  EXPECT_EQ(scene->meshes[0].role, MeshRole::kCasterOnly);
  EXPECT_EQ(scene->meshes[1].role, MeshRole::kReceiverOnly);
  EXPECT_EQ(scene->meshes[2].role, MeshRole::kCasterAndReceiver);
  EXPECT_EQ(scene->meshes[3].role, MeshRole::kCasterAndReceiver);
}

TEST_F(SceneLoaderTest, TransformIsRowMajorWithTranslationInElements3711) {
  // A 90 degree turn about z, a scale of 2 and a translation of (5, 6, 7).
  absl::StatusOr<Scene> scene =
      Load(SceneJson(WithTransform("0,-2,0,5, 2,0,0,6, 0,0,2,7, 0,0,0,1")));
  ASSERT_TRUE(scene.ok()) << scene.status();
  const std::vector<glm::dvec3>& p = scene->meshes[0].positions_world;
  ASSERT_EQ(p.size(), 3u);
  EXPECT_EQ(p[0], glm::dvec3(5, 6, 7));  // (0,0,0)
  EXPECT_EQ(p[1], glm::dvec3(5, 8, 7));  // (1,0,0) -> (0,2,0) + t
  EXPECT_EQ(p[2], glm::dvec3(5, 6, 9));  // (0,0,1) -> (0,0,2) + t
}

TEST_F(SceneLoaderTest, TransformAppliesToMeshFiles) {
  Write("models/thing.ply", kPlyQuad);
  absl::StatusOr<Scene> scene = Load(SceneJson(
      R"({"path": "models/thing.ply", "transform": [1,0,0,100, 0,1,0,0, 0,0,1,0, 0,0,0,1]})"));
  ASSERT_TRUE(scene.ok()) << scene.status();
  for (const glm::dvec3& p : scene->meshes[0].positions_world) {
    EXPECT_TRUE(p.x == 100 || p.x == 101) << p.x;
    EXPECT_EQ(p.y, 1);
  }
}

TEST_F(SceneLoaderTest, FarFromOriginKeepsDoublePrecision) {
  const double t[16] = {0.6, -0.8, 0, 1e6, 0.8, 0.6, 0, -2e6, 0, 0, 1, 1e6 + 0.5, 0, 0, 0, 1};
  const double model[9] = {0.1, 0.2, 0.3, 1.7, -0.01, 0.123456789, -3, 4, 5};
  std::string transform, positions;
  // %.17g: the JSON text must read back to exactly these doubles.
  for (double x : t) {
    absl::StrAppend(&transform, transform.empty() ? "" : ",", absl::StrFormat("%.17g", x));
  }
  for (double x : model) {
    absl::StrAppend(&positions, positions.empty() ? "" : ",", absl::StrFormat("%.17g", x));
  }
  absl::StatusOr<Scene> scene = Load(SceneJson(
      InlineMesh(positions, "0,1,2", absl::StrCat(R"(, "transform": [)", transform, "]"))));
  ASSERT_TRUE(scene.ok()) << scene.status();
  const std::vector<glm::dvec3>& p = scene->meshes[0].positions_world;
  for (int v = 0; v < 3; ++v) {
    const double x = model[3 * v], y = model[3 * v + 1], z = model[3 * v + 2];
    // Exactly transform * p in double, same order of operations.
    EXPECT_EQ(p[v].x, t[0] * x + t[1] * y + t[2] * z + t[3]);
    EXPECT_EQ(p[v].y, t[4] * x + t[5] * y + t[6] * z + t[7]);
    EXPECT_EQ(p[v].z, t[8] * x + t[9] * y + t[10] * z + t[11]);
  }
  // float would round to 1/16 here.
  EXPECT_NEAR(p[0].z - (1e6 + 0.5), 0.3, 1e-9);
}

TEST_F(SceneLoaderTest, RectFrameIsOrthonormalRightHandedAndFollowsUp) {
  // A tilted light with an `up` that is not in its plane.
  const glm::dvec3 up(0.3, 0.4, 2.0);
  absl::StatusOr<Scene> scene =
      Load(SceneJson(kSquare, Rect("1,9,2", "0.2,-1,0.3", "0.3,0.4,2.0", "4,1")));
  ASSERT_TRUE(scene.ok()) << scene.status();
  const LightFrame& f = scene->light.frame;
  EXPECT_NEAR(glm::length(f.u), 1, 1e-12);
  EXPECT_NEAR(glm::length(f.v), 1, 1e-12);
  EXPECT_NEAR(glm::length(f.n), 1, 1e-12);
  EXPECT_NEAR(glm::dot(f.u, f.v), 0, 1e-12);
  EXPECT_NEAR(glm::dot(f.u, f.n), 0, 1e-12);
  EXPECT_NEAR(glm::dot(f.v, f.n), 0, 1e-12);
  const glm::dvec3 uxv = glm::cross(f.u, f.v);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(uxv[i], f.n[i], 1e-12);
  const glm::dvec3 n_expected = glm::normalize(glm::dvec3(0.2, -1, 0.3));
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(f.n[i], n_expected[i], 1e-12);
  const glm::dvec3 up_projected = glm::normalize(up - glm::dot(up, f.n) * f.n);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(f.v[i], up_projected[i], 1e-12);
  EXPECT_EQ(f.center, glm::dvec3(1, 9, 2));
  // Width along u, height along v.
  EXPECT_EQ(scene->light.half_width, 2);
  EXPECT_EQ(scene->light.half_height, 0.5);
}

TEST_F(SceneLoaderTest, DiskAndSunLights) {
  absl::StatusOr<Scene> disk = Load(
      SceneJson(kSquare, R"({"disk": {"center": [2,10,1], "normal": [0,-3,0], "radius": 1.5}})"));
  ASSERT_TRUE(disk.ok()) << disk.status();
  EXPECT_EQ(disk->light.shape, LightShape::kDisk);
  EXPECT_EQ(disk->light.radius, 1.5);
  EXPECT_EQ(disk->light.frame.center, glm::dvec3(2, 10, 1));
  EXPECT_EQ(disk->light.frame.n, glm::dvec3(0, -1, 0));
  EXPECT_NEAR(glm::dot(glm::cross(disk->light.frame.u, disk->light.frame.v), disk->light.frame.n),
              1, 1e-12);

  // A sun 2 degrees across, with a direction of huge components (no overflow in its length),
  // and a frustum that starts behind the light plane (allowed for the sun).
  absl::StatusOr<Scene> sun = Load(SceneJson(
      kSquare, R"({"sun": {"direction": [3e200, -1e201, 2e200], "angularDiameterDeg": 2}})",
      R"({"frustum": {"window": [-5, 5, -5, 5], "depthRange": [-10, 10]}})"));
  ASSERT_TRUE(sun.ok()) << sun.status();
  EXPECT_EQ(sun->light.shape, LightShape::kSun);
  EXPECT_DOUBLE_EQ(sun->light.tan_half_angle, std::tan(std::numbers::pi / 180.0));
  const glm::dvec3 n = glm::normalize(glm::dvec3(0.3, -1, 0.2));
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(sun->light.frame.n[i], n[i], 1e-12);
  EXPECT_EQ(sun->bake.frustum->z_near, -10);
}

TEST_F(SceneLoaderTest, EmptySceneIsValid) {
  absl::StatusOr<Scene> scene = Load(absl::StrCat(R"({"light": )", kRect, "}"));
  ASSERT_TRUE(scene.ok()) << scene.status();
  EXPECT_TRUE(scene->meshes.empty());
  EXPECT_EQ(scene->name, "");
}

TEST_F(SceneLoaderTest, ZeroAreaTrianglesAreKept) {
  absl::StatusOr<Scene> scene = Load(SceneJson(InlineMesh("0,0,0, 1,0,0, 2,0,0", "0,1,2")));
  ASSERT_TRUE(scene.ok()) << scene.status();
  EXPECT_EQ(scene->meshes[0].indices.size(), 3u);
}

TEST_F(SceneLoaderTest, RelativeMeshPathsResolveAgainstTheSceneFolder) {
  Write("models/thing.ply", kPlyQuad);
  const std::string absolute = Write("elsewhere/quad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  const std::string scene_path =
      Write("scenes/deep/scene.json",
            SceneJson(absl::StrCat(R"({"path": "../../models/thing.ply"}, {"path": ")", absolute,
                                   R"("})")));
  // Load from another working directory: the scene's folder, not the cwd, must count.
  const std::filesystem::path cwd = std::filesystem::current_path();
  std::filesystem::current_path(std::filesystem::temp_directory_path());
  absl::StatusOr<Scene> scene = LoadSceneFile(scene_path);
  std::filesystem::current_path(cwd);
  ASSERT_TRUE(scene.ok()) << scene.status();
  ASSERT_EQ(scene->meshes.size(), 2u);
  EXPECT_EQ(scene->meshes[0].indices.size(), 6u);
  EXPECT_EQ(scene->meshes[0].label, "meshes[0] (../../models/thing.ply)");
  EXPECT_EQ(scene->meshes[1].indices.size(), 3u);
}

TEST_F(SceneLoaderTest, SceneFileInTheWorkingDirectory) {
  Write("models/thing.ply", kPlyQuad);
  Write("scene.json", SceneJson(R"({"path": "models/thing.ply"})"));
  const std::filesystem::path cwd = std::filesystem::current_path();
  std::filesystem::current_path(dir_);
  absl::StatusOr<Scene> scene = LoadSceneFile("scene.json");
  std::filesystem::current_path(cwd);
  ASSERT_TRUE(scene.ok()) << scene.status();
  EXPECT_EQ(scene->meshes[0].indices.size(), 6u);
}

TEST_F(SceneLoaderTest, BundledExamplesLoad) {
  const std::filesystem::path examples = PDSM_SOURCE_DIR "/examples";
  if (!std::filesystem::exists(examples)) GTEST_SKIP() << "no examples folder";
  int count = 0;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(examples)) {
    if (entry.path().extension() != ".json") continue;
    absl::StatusOr<Scene> scene = LoadSceneFile(entry.path().string());
    EXPECT_TRUE(scene.ok()) << scene.status();
    ++count;
  }
  if (count == 0) GTEST_SKIP() << "no example scenes";
}

TEST_F(SceneLoaderTest, SharedBunnyScene) {
  const std::string path = PDSM_SHARED_DIR "/scenes/bunny.json";
  if (!std::filesystem::exists(PDSM_SHARED_DIR "/models/bun_zipper.ply") ||
      !std::filesystem::exists(path)) {
    GTEST_SKIP() << "shared bunny scene not present";
  }
  absl::StatusOr<Scene> scene = LoadSceneFile(path);
  ASSERT_TRUE(scene.ok()) << scene.status();
  ASSERT_EQ(scene->meshes.size(), 2u);
  EXPECT_EQ(scene->meshes[0].indices.size(), 3u * 69451);
  EXPECT_EQ(scene->light.shape, LightShape::kDisk);
  EXPECT_EQ(scene->meshes[1].role, MeshRole::kReceiverOnly);
}

// ---- Scene files, parsed only -----------------------------------------------------------

TEST_F(SceneLoaderTest, ParseSceneFileAppliesOverridesAndLoadsNoMesh) {
  pdsm::v1::BakeParams overrides;
  overrides.set_samples(7);
  scene_path_ = Write("scene.json", SceneJson(R"({"path": "models/not-there.ply"})", kRect,
                                              R"({"samples": 16, "tileSize": 32})"));
  absl::StatusOr<pdsm::v1::Scene> message = ParseSceneFile(scene_path_, overrides);
  ASSERT_TRUE(message.ok()) << message.status();
  EXPECT_EQ(message->name(), "test");
  ASSERT_EQ(message->meshes_size(), 1);
  EXPECT_EQ(message->meshes(0).path(), "models/not-there.ply");
  EXPECT_EQ(message->bake().samples(), 7u);
  EXPECT_EQ(message->bake().tile_size(), 32u);
}

TEST_F(SceneLoaderTest, ParseSceneFileErrorsAreThoseOfLoadSceneFile) {
  for (const std::string& json : {std::string(R"({"name": "x", "meshes": [})"), std::string(""),
                                  absl::StrCat(R"({"meshs": [], "light": )", kRect, "}")}) {
    SCOPED_TRACE(json);
    scene_path_ = Write("scene.json", json);
    const absl::Status parsed = ParseSceneFile(scene_path_).status();
    const absl::Status loaded = LoadSceneFile(scene_path_).status();
    EXPECT_EQ(parsed.code(), absl::StatusCode::kInvalidArgument) << parsed;
    EXPECT_EQ(parsed, loaded);
  }
  const std::string absent = (dir_ / "absent.json").string();
  EXPECT_EQ(ParseSceneFile(absent).status().code(), absl::StatusCode::kNotFound);
  EXPECT_EQ(ParseSceneFile(absent).status(), LoadSceneFile(absent).status());
}

TEST_F(SceneLoaderTest, ResolveMeshPath) {
  EXPECT_EQ(ResolveMeshPath("/a/b/scene.json", "m.ply"), "/a/b/m.ply");
  EXPECT_EQ(ResolveMeshPath("/a/b/scene.json", "../models/./m.ply"), "/a/models/m.ply");
  EXPECT_EQ(ResolveMeshPath("/a/b/scene.json", "/elsewhere/m.ply"), "/elsewhere/m.ply");
  EXPECT_EQ(ResolveMeshPath("scenes/scene.json", "m.ply"), "scenes/m.ply");
  EXPECT_EQ(ResolveMeshPath("scene.json", "models/m.ply"), "models/m.ply");
}

// ---- Meshes from assets -----------------------------------------------------------------

// Awkward coordinates on purpose, and a quad that the importer triangulates.
constexpr char kObjMesh[] =
    "v 0.1 0.2 0.3\n"
    "v 1.0000001 -3.14159265358979 2.718281828459045\n"
    "v 123456.789012345 -0.0 0.000012345678\n"
    "v -7.25 1e-7 98765.4321\n"
    "v 0.3333333333333333 0.6666666666666666 -1e-30\n"
    "f 1 2 3\n"
    "f 2 3 4 5\n";

std::string AssetJson(const std::string& sha256) {
  return absl::StrCat(R"({"assetSha256": ")", sha256, R"("})");
}

void ExpectSameBits(double a, double b, const std::string& what) {
  EXPECT_EQ(std::bit_cast<uint64_t>(a), std::bit_cast<uint64_t>(b))
      << what << ": " << a << " vs " << b;
}

void ExpectSameBits(const glm::dvec3& a, const glm::dvec3& b, const std::string& what) {
  for (int c = 0; c < 3; ++c) ExpectSameBits(a[c], b[c], absl::StrCat(what, "[", c, "]"));
}

// Everything a bake reads, bit for bit. Labels differ by design: they say where a mesh came from.
void ExpectSameScene(const Scene& a, const Scene& b) {
  EXPECT_EQ(a.name, b.name);
  EXPECT_EQ(a.source_path, b.source_path);
  EXPECT_EQ(a.light.shape, b.light.shape);
  ExpectSameBits(a.light.frame.center, b.light.frame.center, "light.frame.center");
  ExpectSameBits(a.light.frame.u, b.light.frame.u, "light.frame.u");
  ExpectSameBits(a.light.frame.v, b.light.frame.v, "light.frame.v");
  ExpectSameBits(a.light.frame.n, b.light.frame.n, "light.frame.n");
  ExpectSameBits(a.light.half_width, b.light.half_width, "light.half_width");
  ExpectSameBits(a.light.half_height, b.light.half_height, "light.half_height");
  ExpectSameBits(a.light.radius, b.light.radius, "light.radius");
  ExpectSameBits(a.light.tan_half_angle, b.light.tan_half_angle, "light.tan_half_angle");
  EXPECT_EQ(a.bake.width, b.bake.width);
  EXPECT_EQ(a.bake.height, b.bake.height);
  EXPECT_EQ(a.bake.samples, b.bake.samples);
  EXPECT_EQ(a.bake.shadow_map_resolution, b.bake.shadow_map_resolution);
  ExpectSameBits(a.bake.epsilon, b.bake.epsilon, "bake.epsilon");
  EXPECT_EQ(a.bake.depth_bias, b.bake.depth_bias);
  ExpectSameBits(a.bake.slope_bias, b.bake.slope_bias, "bake.slope_bias");
  EXPECT_EQ(a.bake.tile_size, b.bake.tile_size);
  EXPECT_EQ(a.bake.seed, b.bake.seed);
  EXPECT_EQ(a.bake.sampling, b.bake.sampling);
  EXPECT_EQ(a.bake.compression_metric, b.bake.compression_metric);
  ASSERT_EQ(a.bake.frustum.has_value(), b.bake.frustum.has_value());
  if (a.bake.frustum.has_value()) {
    ExpectSameBits(a.bake.frustum->s_min, b.bake.frustum->s_min, "frustum.s_min");
    ExpectSameBits(a.bake.frustum->s_max, b.bake.frustum->s_max, "frustum.s_max");
    ExpectSameBits(a.bake.frustum->t_min, b.bake.frustum->t_min, "frustum.t_min");
    ExpectSameBits(a.bake.frustum->t_max, b.bake.frustum->t_max, "frustum.t_max");
    ExpectSameBits(a.bake.frustum->z_near, b.bake.frustum->z_near, "frustum.z_near");
    ExpectSameBits(a.bake.frustum->z_far, b.bake.frustum->z_far, "frustum.z_far");
  }
  ASSERT_EQ(a.meshes.size(), b.meshes.size());
  for (size_t m = 0; m < a.meshes.size(); ++m) {
    SCOPED_TRACE(absl::StrCat("meshes[", m, "]"));
    EXPECT_EQ(a.meshes[m].role, b.meshes[m].role);
    EXPECT_EQ(a.meshes[m].indices, b.meshes[m].indices);
    ASSERT_EQ(a.meshes[m].positions_world.size(), b.meshes[m].positions_world.size());
    for (size_t v = 0; v < a.meshes[m].positions_world.size(); ++v) {
      ExpectSameBits(a.meshes[m].positions_world[v], b.meshes[m].positions_world[v],
                     absl::StrCat("positions_world[", v, "]"));
    }
  }
}

class SceneAssetTest : public SceneLoaderTest {
 protected:
  void SetUp() override {
    absl::StatusOr<std::unique_ptr<AssetStore>> store =
        AssetStore::Open((dir_ / "assets").string());
    ASSERT_TRUE(store.ok()) << store.status();
    store_ = *std::move(store);
    resolver_ = [this](const std::string& sha256,
                       const std::string& context) -> absl::StatusOr<MeshFileData> {
      contexts_.push_back(context);
      absl::StatusOr<std::string> bytes = store_->Get(sha256);
      if (!bytes.ok()) return bytes.status();
      return DecodeMeshAsset(*bytes, context);
    };
  }

  // What `pdsm submit` does: every path mesh becomes an uploaded asset.
  void PathsToAssets(const std::string& scene_path, pdsm::v1::Scene* message) {
    for (pdsm::v1::Mesh& mesh : *message->mutable_meshes()) {
      if (mesh.source_case() != pdsm::v1::Mesh::kPath) continue;
      absl::StatusOr<MeshFileData> data =
          LoadMeshFile(ResolveMeshPath(scene_path, mesh.path()), "upload");
      ASSERT_TRUE(data.ok()) << data.status();
      const std::string bytes = EncodeMeshAsset(*data);
      const std::string sha256 = Sha256Hex(bytes);
      ASSERT_TRUE(store_->Put(sha256, bytes).ok());
      mesh.set_asset_sha256(sha256);
    }
  }

  std::unique_ptr<AssetStore> store_;
  MeshAssetResolver resolver_;
  std::vector<std::string> contexts_;  // every call of resolver_
};

TEST_F(SceneAssetTest, EncodedMeshFileDecodesBitForBit) {
  const std::string path = Write("models/awkward.obj", kObjMesh);
  absl::StatusOr<MeshFileData> file = LoadMeshFile(path, "test");
  ASSERT_TRUE(file.ok()) << file.status();
  absl::StatusOr<MeshFileData> asset = DecodeMeshAsset(EncodeMeshAsset(*file), "test");
  ASSERT_TRUE(asset.ok()) << asset.status();
  ASSERT_EQ(asset->positions.size(), file->positions.size());
  for (size_t v = 0; v < file->positions.size(); ++v) {
    ExpectSameBits(asset->positions[v], file->positions[v], absl::StrCat("vertex ", v));
  }
  EXPECT_EQ(asset->indices, file->indices);
}

TEST_F(SceneAssetTest, SceneFromAssetsEqualsSceneFromMeshFiles) {
  Write("models/awkward.obj", kObjMesh);
  Write("models/thing.ply", kPlyQuad);
  scene_path_ = Write("scenes/scene.json", R"({
    "name": "assets",
    "meshes": [
      {"path": "../models/awkward.obj",
       "transform": [0.8, 0.6, 0, 1000.125, -0.6, 0.8, 0, 0.1, 0, 0, 2, -3.3, 0, 0, 0, 1],
       "role": "CASTER_ONLY"},
      {"inline": {"positions": [-10,0,-10, 10,0,-10, 10,0,10], "indices": [0,1,2]},
       "role": "RECEIVER_ONLY"},
      {"path": "../models/thing.ply"}
    ],
    "light": {"disk": {"center": [0.1,10,0.2], "normal": [0.1,-1,0.05], "radius": 0.7}},
    "bake": {"resolution": [300, 200], "samples": 9, "epsilon": 0.02, "seed": "77",
             "frustum": {"window": [-0.5, 0.5, -0.25, 0.75], "depthRange": [1, 20]}}
  })");
  pdsm::v1::BakeParams overrides;
  overrides.set_samples(33);

  absl::StatusOr<Scene> from_files = LoadSceneFile(scene_path_, overrides);
  ASSERT_TRUE(from_files.ok()) << from_files.status();

  absl::StatusOr<pdsm::v1::Scene> message = ParseSceneFile(scene_path_, overrides);
  ASSERT_TRUE(message.ok()) << message.status();
  PathsToAssets(scene_path_, &*message);
  ASSERT_EQ(message->meshes(0).source_case(), pdsm::v1::Mesh::kAssetSha256);
  ASSERT_EQ(message->meshes(2).source_case(), pdsm::v1::Mesh::kAssetSha256);
  // No base folder: the coordinator opens no path; assets only.
  absl::StatusOr<Scene> from_assets = SceneFromProto(*message, scene_path_, "", resolver_);
  ASSERT_TRUE(from_assets.ok()) << from_assets.status();

  ExpectSameScene(*from_files, *from_assets);
  EXPECT_EQ(from_assets->bake.samples, 33);
  EXPECT_EQ(
      from_assets->meshes[0].label,
      absl::StrCat("meshes[0] (asset ", message->meshes(0).asset_sha256().substr(0, 12), ")"));
  EXPECT_EQ(from_assets->meshes[1].label, "meshes[1] (inline)");
  EXPECT_EQ(contexts_,
            (std::vector<std::string>{absl::StrCat(scene_path_, ": meshes[0].assetSha256"),
                                      absl::StrCat(scene_path_, ": meshes[2].assetSha256")}));
}

TEST_F(SceneAssetTest, SceneFileWithAnAssetIsRefused) {
  const std::string sha256 = Sha256Hex("abc");
  ExpectInvalid(Load(SceneJson(AssetJson(sha256))), "meshes[0].assetSha256",
                "mesh assets are only accepted by the coordinator; use path or inline");
}

TEST_F(SceneAssetTest, ProtoWithoutResolverRefusesAssets) {
  absl::StatusOr<pdsm::v1::Scene> message = ParseSceneFile(
      Write("scene.json", SceneJson(absl::StrCat(kSquare, ", ", AssetJson(Sha256Hex("abc"))))));
  ASSERT_TRUE(message.ok()) << message.status();
  for (const MeshAssetResolver& none : {MeshAssetResolver(), MeshAssetResolver(nullptr)}) {
    absl::StatusOr<Scene> scene = SceneFromProto(*message, "job 7", "", none);
    ASSERT_EQ(scene.status().code(), absl::StatusCode::kInvalidArgument) << scene.status();
    EXPECT_EQ(scene.status().message(),
              "job 7: meshes[1].assetSha256: mesh assets are only accepted by the coordinator; "
              "use path or inline");
  }
  absl::StatusOr<Scene> scene = SceneFromProto(*message, "job 7", "");  // the default
  EXPECT_EQ(scene.status().code(), absl::StatusCode::kInvalidArgument) << scene.status();
}

TEST_F(SceneAssetTest, MalformedHashIsRefusedNamingTheField) {
  const std::string good = Sha256Hex("abc");
  std::string upper = good;
  upper[5] = 'C';
  for (const std::string& bad : {std::string(""), good.substr(0, 63), good + "a", upper,
                                 std::string("../../etc/passwd"), std::string(500, 'z')}) {
    SCOPED_TRACE(bad);
    absl::StatusOr<pdsm::v1::Scene> parsed = ParseSceneFile(Write("scene.json", SceneJson()));
    ASSERT_TRUE(parsed.ok()) << parsed.status();
    pdsm::v1::Scene message = *std::move(parsed);
    message.add_meshes()->set_asset_sha256(bad);
    absl::StatusOr<Scene> scene = SceneFromProto(message, "job 7", "", resolver_);
    ASSERT_EQ(scene.status().code(), absl::StatusCode::kInvalidArgument) << scene.status();
    EXPECT_THAT(scene.status().message(),
                HasSubstr("job 7: meshes[1].assetSha256: must be a SHA-256, 64 lowercase hex "
                          "digits (got \""));
    EXPECT_LT(scene.status().message().size(), 250u);  // a long value is cut short
  }
  EXPECT_TRUE(contexts_.empty()) << "the resolver must not see a malformed hash";
}

TEST_F(SceneAssetTest, ResolverErrorsArePassedOn) {
  const std::string json = SceneJson(AssetJson(Sha256Hex("never uploaded")));
  absl::StatusOr<pdsm::v1::Scene> message = ParseSceneFile(Write("scene.json", json));
  ASSERT_TRUE(message.ok()) << message.status();
  absl::StatusOr<Scene> scene = SceneFromProto(*message, "job 7", "", resolver_);
  EXPECT_EQ(scene.status().code(), absl::StatusCode::kNotFound) << scene.status();
  EXPECT_THAT(scene.status().message(), HasSubstr(Sha256Hex("never uploaded")));

  // An uploaded blob that is not a mesh: the decoder's message, prefixed with the field.
  const std::string junk = "not a mesh";
  ASSERT_TRUE(store_->Put(Sha256Hex(junk), junk).ok());
  message->mutable_meshes(0)->set_asset_sha256(Sha256Hex(junk));
  scene = SceneFromProto(*message, "job 7", "", resolver_);
  EXPECT_EQ(scene.status().code(), absl::StatusCode::kInvalidArgument) << scene.status();
  EXPECT_THAT(scene.status().message(),
              HasSubstr("job 7: meshes[0].assetSha256: not a mesh asset (bad magic)"));
}

TEST_F(SceneAssetTest, AssetMeshesStillTakeTransformAndRole) {
  MeshFileData triangle;
  triangle.positions = {{0, 0, 0}, {1, 0, 0}, {0, 0, 1}};
  triangle.indices = {0, 1, 2};
  const std::string bytes = EncodeMeshAsset(triangle);
  const std::string sha256 = Sha256Hex(bytes);
  ASSERT_TRUE(store_->Put(sha256, bytes).ok());
  absl::StatusOr<pdsm::v1::Scene> message = ParseSceneFile(
      Write("scene.json",
            SceneJson(absl::StrCat(R"({"assetSha256": ")", sha256,
                                   R"(", "role": "CASTER_ONLY", )"
                                   R"("transform": [1,0,0,5, 0,1,0,6, 0,0,1,7, 0,0,0,1]})"))));
  ASSERT_TRUE(message.ok()) << message.status();
  absl::StatusOr<Scene> scene = SceneFromProto(*message, "job 7", "", resolver_);
  ASSERT_TRUE(scene.ok()) << scene.status();
  EXPECT_EQ(scene->meshes[0].role, MeshRole::kCasterOnly);
  EXPECT_EQ(scene->meshes[0].positions_world[1], glm::dvec3(6, 6, 7));
  EXPECT_EQ(scene->meshes[0].label, absl::StrCat("meshes[0] (asset ", sha256.substr(0, 12), ")"));
}

}  // namespace
}  // namespace pdsm

// ---- Several lights ---------------------------------------------------------------------

namespace pdsm {
namespace {

constexpr char kSun[] = R"({"direction": [0,-1,0], "angularDiameterDeg": 0.53})";

// A scene with `lights` (the JSON array's contents) and `bake`.
std::string LightsJson(const std::string& lights, const std::string& bake = "{}") {
  return absl::StrCat(R"({"name": "world", "meshes": [)", kSquare, R"(], "lights": [)", lights,
                      R"(], "bake": )", bake, "}");
}

TEST_F(SceneLoaderTest, LightsLoadInOrderWithTheirNames) {
  absl::StatusOr<Scene> scene = Load(LightsJson(absl::StrCat(
      R"({"name": "sun", "sun": )", kSun,
      R"(}, {"name": "lamp_1", "rect": {"center": [0,10,0], "normal": [0,-1,0], "up": [0,0,1],)",
      R"( "size": [3,2]}}, {"name": "lamp.2-b", "disk": {"center": [1,5,1], "normal": [0,-1,0], "radius": 0.25}})")));
  ASSERT_TRUE(scene.ok()) << scene.status();
  ASSERT_EQ(scene->LightCount(), 3u);
  EXPECT_EQ(scene->light_name, "sun");
  EXPECT_EQ(scene->light.shape, LightShape::kSun);
  EXPECT_EQ(scene->more_lights[0].name, "lamp_1");
  EXPECT_EQ(scene->more_lights[0].spec.shape, LightShape::kRect);
  EXPECT_EQ(scene->more_lights[1].name, "lamp.2-b");
  EXPECT_DOUBLE_EQ(scene->more_lights[1].spec.radius, 0.25);
  EXPECT_EQ(FindLight(*scene, "lamp.2-b"), 2);
  EXPECT_EQ(FindLight(*scene, "moon"), -1);

  const Scene second = ForLight(*scene, 1);
  EXPECT_EQ(second.LightCount(), 1u);
  EXPECT_EQ(second.light_name, "lamp_1");
  EXPECT_EQ(second.light.shape, LightShape::kRect);
  EXPECT_EQ(second.meshes.size(), scene->meshes.size());
  EXPECT_EQ(second.name, "world");
}

TEST_F(SceneLoaderTest, EachLightTakesTheScenesBakeAndItsOwnAndOverridesWin) {
  const std::string json =
      LightsJson(absl::StrCat(R"({"name": "a", "sun": )", kSun,
                              R"(, "bake": {"samples": 8, "epsilon": 0.05}},)",
                              R"({"name": "b", "sun": )", kSun, "}"),
                 R"({"samples": 32, "resolution": [64, 48], "epsilon": 0.02})");
  absl::StatusOr<Scene> scene = Load(json);
  ASSERT_TRUE(scene.ok()) << scene.status();
  EXPECT_EQ(scene->bake.samples, 8);  // a's own
  EXPECT_DOUBLE_EQ(scene->bake.epsilon, 0.05);
  EXPECT_EQ(scene->bake.width, 64);  // the scene's
  EXPECT_EQ(scene->more_lights[0].bake.samples, 32);
  EXPECT_DOUBLE_EQ(scene->more_lights[0].bake.epsilon, 0.02);
  // A command-line flag replaces the light's own value too.
  pdsm::v1::BakeParams overrides;
  overrides.set_samples(4);
  absl::StatusOr<Scene> overridden = Load(json, overrides);
  ASSERT_TRUE(overridden.ok()) << overridden.status();
  EXPECT_EQ(overridden->bake.samples, 4);
  EXPECT_EQ(overridden->more_lights[0].bake.samples, 4);
  EXPECT_DOUBLE_EQ(overridden->bake.epsilon, 0.05);  // not overridden: still a's
}

TEST_F(SceneLoaderTest, OneLightFormTakesANameAndItsOwnBake) {
  absl::StatusOr<Scene> scene =
      Load(absl::StrCat(R"({"meshes": [], "light": {"name": "key", "sun": )", kSun,
                        R"(, "bake": {"samples": 12}}, "bake": {"samples": 40}})"));
  ASSERT_TRUE(scene.ok()) << scene.status();
  EXPECT_EQ(scene->LightCount(), 1u);
  EXPECT_EQ(scene->light_name, "key");
  EXPECT_EQ(scene->bake.samples, 12);
}

TEST_F(SceneLoaderTest, BadLightsNameTheEntryAndField) {
  const std::string sun = absl::StrCat(R"("sun": )", kSun);
  ExpectInvalid(Load(LightsJson(absl::StrCat("{", sun, "}, {", sun, R"(, "name": "b"})"))),
                "lights[0].name", "required when the scene has several lights");
  ExpectInvalid(
      Load(LightsJson(absl::StrCat(R"({"name": "a", )", sun, R"(}, {"name": "a", )", sun, "}"))),
      "lights[1].name", "\"a\" names another light already");
  ExpectInvalid(Load(LightsJson(absl::StrCat(R"({"name": "a b", )", sun, "}"))), "lights[0].name",
                "only letters, digits");
  ExpectInvalid(
      Load(LightsJson(absl::StrCat(R"({"name": ")", std::string(65, 'x'), R"(", )", sun, "}"))),
      "lights[0].name", "at most 64 bytes");
  ExpectInvalid(
      Load(LightsJson(absl::StrCat(
          R"({"name": "a", )", sun,
          R"(}, {"name": "b", "disk": {"center": [0,5,0], "normal": [0,-1,0], "radius": 0}})"))),
      "lights[1].disk.radius", "must be > 0 (got 0)");
  ExpectInvalid(
      Load(LightsJson(absl::StrCat(R"({"name": "a", )", sun, R"(, "bake": {"samples": 0}})"))),
      "lights[0].bake.samples", "(got 0)");
  // A bad value in the scene's bake stays the scene's, even for a light with a bake of its own.
  ExpectInvalid(
      Load(LightsJson(absl::StrCat(R"({"name": "a", )", sun, R"(, "bake": {"samples": 2}})"),
                      R"({"epsilon": 7})")),
      "bake.epsilon", "(got 7)");
  ExpectInvalid(Load(LightsJson(R"({"name": "a"})")), "lights[0]",
                "one of rect, disk, spot, sphere, sun");
  ExpectInvalid(
      Load(absl::StrCat(R"({"meshes": [], "light": {)", sun, R"(}, "lights": [{)", sun, "}]}")),
      "lights", "either light (one light) or lights");
}

TEST_F(SceneLoaderTest, OneLightSelectsOrNamesTheLights) {
  const std::string sun = absl::StrCat(R"("sun": )", kSun);
  absl::StatusOr<Scene> scene =
      Load(LightsJson(absl::StrCat(R"({"name": "a", )", sun, R"(}, {"name": "b", )", sun, "}")));
  ASSERT_TRUE(scene.ok()) << scene.status();
  absl::StatusOr<Scene> b = OneLight(*scene, "b", "test");
  ASSERT_TRUE(b.ok()) << b.status();
  EXPECT_EQ(b->light_name, "b");
  EXPECT_EQ(b->LightCount(), 1u);
  absl::StatusOr<Scene> none = OneLight(*scene, "", "pdsm reference");
  EXPECT_EQ(none.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(none.status().message(), HasSubstr("pdsm reference works on one light"));
  EXPECT_THAT(none.status().message(), HasSubstr("(\"a\", \"b\")"));
  EXPECT_THAT(OneLight(*scene, "c", "test").status().message(), HasSubstr("no light \"c\""));
}

}  // namespace
}  // namespace pdsm

namespace pdsm {
namespace {

TEST_F(SceneLoaderTest, SpotIsADiskWithACone) {
  absl::StatusOr<Scene> scene = Load(SceneJson(
      kSquare,
      R"({"spot": {"center": [0,5,0], "normal": [0,-2,0], "radius": 0.5, "coneHalfAngleDeg": 30}})"));
  ASSERT_TRUE(scene.ok()) << scene.status();
  EXPECT_EQ(scene->light.shape, LightShape::kDisk);
  EXPECT_TRUE(scene->light.is_spot());
  EXPECT_DOUBLE_EQ(scene->light.radius, 0.5);
  EXPECT_DOUBLE_EQ(scene->light.cone_half_angle_deg, 30);
  EXPECT_DOUBLE_EQ(scene->light.frame.n.y, -1);
  absl::StatusOr<Scene> disk = Load(
      SceneJson(kSquare, R"({"disk": {"center": [0,5,0], "normal": [0,-1,0], "radius": 0.5}})"));
  ASSERT_TRUE(disk.ok());
  EXPECT_FALSE(disk->light.is_spot());
}

TEST_F(SceneLoaderTest, BadSpotNamesTheSpotsFields) {
  const auto spot = [](const std::string& radius, const std::string& cone) {
    return absl::StrCat(R"({"spot": {"center": [0,5,0], "normal": [0,-1,0], "radius": )", radius,
                        R"(, "coneHalfAngleDeg": )", cone, "}}");
  };
  ExpectInvalid(Load(SceneJson(kSquare, spot("0", "30"))), "light.spot.radius", "(got 0)");
  ExpectInvalid(Load(SceneJson(kSquare, spot("1", "0"))), "light.spot.coneHalfAngleDeg",
                "must be in (0, 85] degrees (got 0)");
  ExpectInvalid(Load(SceneJson(kSquare, spot("1", "86"))), "light.spot.coneHalfAngleDeg",
                "(got 86)");
  ExpectInvalid(Load(LightsJson(absl::StrCat(R"({"name": "a", "sun": )", kSun,
                                             R"(}, {"name": "b", )", spot("1", "90").substr(1)))),
                "lights[1].spot.coneHalfAngleDeg", "(got 90)");
  ExpectInvalid(
      Load(SceneJson(
          kSquare,
          R"({"spot": {"center": [0,5,0], "normal": [0,0,0], "radius": 1, "coneHalfAngleDeg": 10}})")),
      "light.spot.normal", "must be non-zero");
}

}  // namespace
}  // namespace pdsm
