#include "core/scene/scene_loader.h"

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
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

  absl::StatusOr<Scene> Load(const std::string& json,
                             const pdsm::v1::BakeParams& overrides = {}) {
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
  return absl::StrCat(R"({"inline": {"positions": [)", positions, R"(], "indices": [)",
                      indices, "]}", extra, "}");
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
  return absl::StrCat(R"({"sun": {"direction": [0,-1,0], "angularDiameterDeg": )", degrees,
                      "}}");
}

// Prefixed "SceneLoader" so that --gtest_filter='Scene*' selects these too.
INSTANTIATE_TEST_SUITE_P(
    SceneLoader, SceneLoaderBadInputTest,
    ::testing::Values(
        BadCase{"NanPosition", InlineMesh(R"(0,"NaN",0, 1,0,0, 0,0,1)", "0,1,2"), kRect, "{}",
                "meshes[0].inline.positions[1]", "must be finite (got NaN)"},
        BadCase{"InfinityPosition", InlineMesh(R"(0,0,0, 1,"Infinity",0, 0,0,1)", "0,1,2"),
                kRect, "{}", "meshes[0].inline.positions[4]", "(got Infinity)"},
        BadCase{"NanTransform", WithTransform(R"(1,0,0,"NaN", 0,1,0,0, 0,0,1,0, 0,0,0,1)"),
                kRect, "{}", "meshes[0].transform[3]", "(got NaN)"},
        BadCase{"InfinityTransform",
                WithTransform(R"(1,0,0,0, 0,"-Infinity",0,0, 0,0,1,0, 0,0,0,1)"), kRect, "{}",
                "meshes[0].transform[5]", "(got -Infinity)"},
        BadCase{"NanLightCenter", kSquare, Rect(R"("NaN",10,0)", "0,-1,0", "0,0,1", "1,1"),
                "{}", "light.rect.center[0]", "(got NaN)"},
        BadCase{"InfinityLightCenter", kSquare,
                Rect(R"(0,"Infinity",0)", "0,-1,0", "0,0,1", "1,1"), "{}",
                "light.rect.center[1]", "(got Infinity)"},
        BadCase{"ZeroRectWidth", kSquare, Rect("0,10,0", "0,-1,0", "0,0,1", "0,1"), "{}",
                "light.rect.size[0]", "must be > 0 (got 0)"},
        BadCase{"NegativeRectHeight", kSquare, Rect("0,10,0", "0,-1,0", "0,0,1", "1,-2"),
                "{}", "light.rect.size[1]", "(got -2)"},
        BadCase{"RectSizeCount", kSquare, Rect("0,10,0", "0,-1,0", "0,0,1", "1"), "{}",
                "light.rect.size", "(got 1)"},
        BadCase{"ZeroNormal", kSquare, Rect("0,10,0", "0,0,0", "0,0,1", "1,1"), "{}",
                "light.rect.normal", "must be non-zero"},
        BadCase{"UpParallelToNormal", kSquare, Rect("0,10,0", "0,-1,0", "0,3,0", "1,1"),
                "{}", "light.rect.up", "parallel"},
        BadCase{"MissingUp", kSquare,
                R"({"rect": {"center": [0,10,0], "normal": [0,-1,0], "size": [1,1]}})", "{}",
                "light.rect.up", "must have 3 numbers (got 0)"},
        BadCase{"DiskRadiusZero", kSquare,
                R"({"disk": {"center": [0,10,0], "normal": [0,-1,0], "radius": 0}})", "{}",
                "light.disk.radius", "must be > 0 (got 0)"},
        BadCase{"SunAngleZero", kSquare, Sun("0"), "{}", "light.sun.angularDiameterDeg",
                "(got 0)"},
        BadCase{"SunAngleNinety", kSquare, Sun("90"), "{}", "light.sun.angularDiameterDeg",
                "must be in (0, 90) degrees (got 90)"},
        BadCase{"NoLight", kSquare, "{}", "{}", "light", "one of rect, disk, sun is required"},
        BadCase{"SamplesZero", kSquare, kRect, R"({"samples": 0})", "bake.samples",
                "must be in [1, 65536] (got 0)"},
        BadCase{"SamplesTooMany", kSquare, kRect, R"({"samples": 65537})", "bake.samples",
                "(got 65537)"},
        BadCase{"ResolutionZero", kSquare, kRect, R"({"resolution": [0, 10]})",
                "bake.resolution[0]", "must be in [1, 16384] (got 0)"},
        BadCase{"ResolutionTooLarge", kSquare, kRect, R"({"resolution": [20000, 10]})",
                "bake.resolution[0]", "(got 20000)"},
        BadCase{"ResolutionCount", kSquare, kRect, R"({"resolution": [1]})", "bake.resolution",
                "must have 2 numbers [width, height] (got 1)"},
        BadCase{"ShadowMapResolutionZero", kSquare, kRect, R"({"shadowMapResolution": 0})",
                "bake.shadowMapResolution", "(got 0)"},
        BadCase{"EpsilonNegative", kSquare, kRect, R"({"epsilon": -0.1})", "bake.epsilon",
                "must be in [0, 1] (got -0.1)"},
        BadCase{"EpsilonAboveOne", kSquare, kRect, R"({"epsilon": 1.5})", "bake.epsilon",
                "(got 1.5)"},
        BadCase{"EpsilonNan", kSquare, kRect, R"({"epsilon": "NaN"})", "bake.epsilon",
                "(got NaN)"},
        BadCase{"TileSizeZero", kSquare, kRect, R"({"tileSize": 0})", "bake.tileSize",
                "(got 0)"},
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
                R"({"frustum": {"window": [1,2,3], "depthRange": [1,2]}})",
                "bake.frustum.window", "(got 3)"},
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
        BadCase{"TransformFifteenNumbers",
                WithTransform("1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0"), kRect, "{}",
                "meshes[0].transform", "must have 0 or 16 numbers (got 15)"},
        BadCase{"SingularTransform", WithTransform("1,0,0,0, 0,0,0,0, 0,0,1,0, 0,0,0,1"),
                kRect, "{}", "meshes[0].transform", "invertible"},
        BadCase{"NearlySingularTransform",
                WithTransform("1e6,0,0,0, 1e6,1e-9,0,0, 0,0,1,0, 0,0,0,1"), kRect, "{}",
                "meshes[0].transform", "invertible"},
        BadCase{"ColumnMajorTransform", WithTransform("1,0,0,0, 0,1,0,0, 0,0,1,0, 5,6,7,1"),
                kRect, "{}", "meshes[0].transform", "translation in elements 3, 7, 11"},
        BadCase{"MeshWithoutSource", R"({"role": "CASTER_ONLY"})", kRect, "{}", "meshes[0]",
                "one of path, inline is required"},
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
  absl::StatusOr<Scene> scene = Load(SceneJson(
      kSquare,
      R"({"rect": {"center": [0,10,0], "normal": [0,-1,0], "up": [0,0,1], "size": [1,1]},
          "disk": {"center": [0,10,0], "normal": [0,-1,0], "radius": 1}})"));
  ASSERT_EQ(scene.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(scene.status().message(),
              HasSubstr(absl::StrCat(scene_path_, ": invalid scene JSON: ")));
  EXPECT_THAT(scene.status().message(), HasSubstr("light"));
  EXPECT_THAT(scene.status().message(), HasSubstr("shape"));
}

TEST_F(SceneLoaderTest, PathAndInlineTogetherIsAnError) {
  absl::StatusOr<Scene> scene = Load(SceneJson(
      R"({"path": "a.ply", "inline": {"positions": [0,0,0], "indices": []}})"));
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
  EXPECT_EQ(scene->bake.sampling, SamplingPattern::kStratified);
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
      "resolution": [16384, 1], "samples": 65536, "shadowMapResolution": 16384,
      "epsilon": 1, "tileSize": 4096})"));
  ASSERT_TRUE(scene.ok()) << scene.status();
  EXPECT_EQ(scene->bake.samples, kMaxSamples);
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
  absl::StatusOr<Scene> scene = Load(
      SceneJson(kSquare, kRect,
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
  absl::StatusOr<Scene> scene = Load(SceneJson(absl::StrCat(
      InlineMesh(kTri, "0,1,2", R"(, "role": "CASTER_ONLY")"), ", ",
      InlineMesh(kTri, "0,1,2", R"(, "role": "RECEIVER_ONLY")"), ", ",
      InlineMesh(kTri, "0,1,2", R"(, "role": "CASTER_AND_RECEIVER")"), ", ",
      InlineMesh(kTri, "0,1,2"))));
  ASSERT_TRUE(scene.ok()) << scene.status();
  ASSERT_EQ(scene->meshes.size(), 4u);
  EXPECT_EQ(scene->meshes[0].role, MeshRole::kCasterOnly);
  EXPECT_EQ(scene->meshes[1].role, MeshRole::kReceiverOnly);
  EXPECT_EQ(scene->meshes[2].role, MeshRole::kCasterAndReceiver);
  EXPECT_EQ(scene->meshes[3].role, MeshRole::kCasterAndReceiver);
}

TEST_F(SceneLoaderTest, TransformIsRowMajorWithTranslationInElements3711) {
  // A 90 degree turn about z, a scale of 2 and a translation of (5, 6, 7).
  absl::StatusOr<Scene> scene = Load(SceneJson(WithTransform(
      "0,-2,0,5, 2,0,0,6, 0,0,2,7, 0,0,0,1")));
  ASSERT_TRUE(scene.ok()) << scene.status();
  const std::vector<glm::dvec3>& p = scene->meshes[0].positions_world;
  ASSERT_EQ(p.size(), 3u);
  EXPECT_EQ(p[0], glm::dvec3(5, 6, 7));      // (0,0,0)
  EXPECT_EQ(p[1], glm::dvec3(5, 8, 7));      // (1,0,0) -> (0,2,0) + t
  EXPECT_EQ(p[2], glm::dvec3(5, 6, 9));      // (0,0,1) -> (0,0,2) + t
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
  absl::StatusOr<Scene> scene = Load(SceneJson(InlineMesh(
      positions, "0,1,2", absl::StrCat(R"(, "transform": [)", transform, "]"))));
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
  absl::StatusOr<Scene> disk = Load(SceneJson(
      kSquare, R"({"disk": {"center": [2,10,1], "normal": [0,-3,0], "radius": 1.5}})"));
  ASSERT_TRUE(disk.ok()) << disk.status();
  EXPECT_EQ(disk->light.shape, LightShape::kDisk);
  EXPECT_EQ(disk->light.radius, 1.5);
  EXPECT_EQ(disk->light.frame.center, glm::dvec3(2, 10, 1));
  EXPECT_EQ(disk->light.frame.n, glm::dvec3(0, -1, 0));
  EXPECT_NEAR(glm::dot(glm::cross(disk->light.frame.u, disk->light.frame.v),
                       disk->light.frame.n), 1, 1e-12);

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
  const std::string scene_path = Write(
      "scenes/deep/scene.json",
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

}  // namespace
}  // namespace pdsm
