// A world file as the scene (issue #16 item 1): the bundled glTF world (examples/world,
// written by make_world.py) bakes with the lights it holds, as a scene JSON would name them.
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <glm/glm.hpp>

#include "absl/strings/str_cat.h"
#include "core/pdsm/pdsm_file.h"
#include "core/pdsm/pdsm_lights.h"
#include "core/pdsm/pdsm_query.h"
#include "core/pdsm/pdsm_tile_cache.h"
#include "core/reference/reference_attenuation.h"
#include "core/scene/scene_loader.h"
#include "core/scene/sphere_faces.h"
#include "core/scene/world_file.h"
#include "tests/test_support.h"
#include "worker/local_bake.h"

namespace pdsm {
namespace {

using testing::TempDir;

std::string WorldPath() { return std::string(PDSM_SOURCE_DIR) + "/examples/world/world.gltf"; }

void WriteText(const std::string& path, const std::string& text) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  ASSERT_NE(f, nullptr) << path;
  std::fputs(text.c_str(), f);
  std::fclose(f);
}

glm::dvec3 Vec3(const google::protobuf::RepeatedField<double>& v) { return {v[0], v[1], v[2]}; }

TEST(WorldFile, LightsComeFromTheFileInWorldSpaceWithTheirExtras) {
  std::vector<std::string> warnings;
  absl::StatusOr<pdsm::v1::Scene> scene = ReadWorldFile(WorldPath(), &warnings);
  ASSERT_TRUE(scene.ok()) << scene.status();
  EXPECT_EQ(scene->name(), "world");
  ASSERT_EQ(scene->meshes_size(), 1);
  EXPECT_EQ(scene->meshes(0).path(), "world.gltf");
  ASSERT_EQ(scene->lights_size(), 3);

  // The sun: its node's rotation takes -Z onto (0.35, -1, 0.25); 2 degrees from its extras.
  const pdsm::v1::Light& sun = scene->lights(0);
  EXPECT_EQ(sun.name(), "sun");
  ASSERT_TRUE(sun.has_sun());
  const glm::dvec3 sun_dir = glm::normalize(glm::dvec3(0.35, -1, 0.25));
  EXPECT_NEAR(glm::length(Vec3(sun.sun().direction()) - sun_dir), 0, 1e-6);
  EXPECT_DOUBLE_EQ(sun.sun().angular_diameter_deg(), 2.0);
  EXPECT_FALSE(sun.has_bake());

  // The spot: at its node's translation, along (0.45, -1, -0.4), the outer cone as its
  // half-angle, radius and samples from its node's extras.
  const pdsm::v1::Light& spot = scene->lights(1);
  EXPECT_EQ(spot.name(), "spot");
  ASSERT_TRUE(spot.has_spot());
  EXPECT_NEAR(glm::length(Vec3(spot.spot().center()) - glm::dvec3(-4, 6, 4)), 0, 1e-6);
  EXPECT_NEAR(glm::length(Vec3(spot.spot().normal()) - glm::normalize(glm::dvec3(0.45, -1, -0.4))),
              0, 1e-6);
  EXPECT_NEAR(spot.spot().cone_half_angle_deg(), 40.0, 1e-4);
  EXPECT_DOUBLE_EQ(spot.spot().radius(), 0.3);
  EXPECT_EQ(spot.bake().samples(), 32);

  // The point light: a sphere at its node's translation, radius and samples from its extras.
  const pdsm::v1::Light& bulb = scene->lights(2);
  EXPECT_EQ(bulb.name(), "bulb");
  ASSERT_TRUE(bulb.has_sphere());
  EXPECT_NEAR(glm::length(Vec3(bulb.sphere().center()) - glm::dvec3(0, 3, 3)), 0, 1e-6);
  EXPECT_DOUBLE_EQ(bulb.sphere().radius(), 0.2);
  EXPECT_EQ(bulb.bake().samples(), 32);
  EXPECT_TRUE(warnings.empty()) << warnings[0];
}

TEST(WorldFile, BakesWithItsLightsAndTheSunShadowsTheGroundBehindTheBox) {
  pdsm::v1::BakeParams overrides;
  overrides.add_resolution(256);
  overrides.add_resolution(256);
  overrides.set_samples(16);
  overrides.set_shadow_map_resolution(512);
  std::vector<std::string> warnings;
  absl::StatusOr<Scene> scene = LoadSceneFile(WorldPath(), overrides, &warnings);
  ASSERT_TRUE(scene.ok()) << scene.status();
  EXPECT_TRUE(warnings.empty());
  ASSERT_EQ(scene->LightCount(), 2u + kSphereFaceCount);  // the sun, the spot, the bulb's faces
  TempDir dir;
  LocalBakeOptions options;
  options.output_path = dir.File("world.exr");
  ASSERT_TRUE(RunLocalBake(*scene, options).ok());
  absl::StatusOr<PdsmImage> sun = ReadPdsm(options.output_path, "sun");
  ASSERT_TRUE(sun.ok()) << sun.status();
  // The box (1 x 1 x 1 at (-2, 0, 1)) casts its top's shadow 0.35, 0.25 along the ground:
  // (-1.3, 0, 1.45) is outside its footprint, in that shadow, 0.15+ from every edge (two
  // pixels); (6, 0, 6) is far from every caster.
  EXPECT_GE(QueryAttenuation(*sun, {-1.3, 0, 1.45}), 0.95);
  EXPECT_EQ(QueryAttenuation(*sun, {6, 0, 6}), 0.0);
  absl::StatusOr<PdsmImage> spot = ReadPdsm(options.output_path, "spot");
  ASSERT_TRUE(spot.ok()) << spot.status();
  EXPECT_EQ(spot->header.samples, 16) << "the command line's samples win over the extras'";
  // The bulb (radius 0.2 at (0, 3, 3)): the box (x -2..-1, z 1..2, top at 1) hides it from the
  // ground at (-2.5, 0, 0.5), seen across its -x and -y faces' boundary; (3, 0, 3), on the +x
  // and -y faces' boundary, is lit.
  absl::StatusOr<PdsmReader> reader = PdsmReader::Open(options.output_path);
  ASSERT_TRUE(reader.ok()) << reader.status();
  absl::StatusOr<PdsmLightParts> bulb =
      FindLightParts(reader->headers(), options.output_path, "bulb");
  ASSERT_TRUE(bulb.ok()) << bulb.status();
  EXPECT_EQ(bulb->parts.size(), size_t{kSphereFaceCount});
  PdsmTileCache cache(*std::move(reader), 16 << 20);
  const std::vector<glm::dvec3> points = {{-2.5, 0, 0.5}, {3, 0, 3}};
  absl::StatusOr<std::vector<double>> a = AttenuationAt(cache, {&*bulb, 1}, points);
  ASSERT_TRUE(a.ok()) << a.status();
  ReferenceOptions embree;
  absl::StatusOr<std::vector<double>> ref =
      ReferenceAttenuation(ForLight(*scene, 2), points, embree);
  ASSERT_TRUE(ref.ok()) << ref.status();
  EXPECT_GT((*a)[0], 0.5);
  EXPECT_EQ((*a)[1], 0.0);
  for (size_t i = 0; i < points.size(); ++i) {
    EXPECT_NEAR((*a)[i], (*ref)[i], 0.1) << points[i].x << "," << points[i].z;
  }
}

// `"lightsFrom": "file"` in a scene JSON: the mesh file's lights join the scene's own, moved
// by the entry's transform (here: scaled by 2 about the origin, then moved 10 along x).
TEST(WorldFile, ASceneJsonTakesAMeshFilesLightsMovedByItsTransform) {
  TempDir dir;
  const std::string scene_path = dir.File("scene.json");
  WriteText(
      scene_path,
      absl::StrCat(R"({"name": "lit", "meshes": [{"path": ")", WorldPath(),
                   R"(", "lightsFrom": "file",)",
                   R"( "transform": [2,0,0,10, 0,2,0,0, 0,0,2,0, 0,0,0,1]}],)",
                   R"( "light": {"rect": {"center": [0,9,0], "normal": [0,-1,0], "up": [0,0,1],)",
                   R"( "size": [1,1]}}})"));
  absl::StatusOr<pdsm::v1::Scene> message = ParseSceneFile(scene_path);
  ASSERT_TRUE(message.ok()) << message.status();
  EXPECT_FALSE(message->has_light());
  ASSERT_EQ(message->lights_size(), 4);
  EXPECT_EQ(message->lights(0).name(), "light");  // the scene's own, named to join a list
  EXPECT_EQ(message->lights(1).name(), "sun");
  EXPECT_EQ(message->lights(2).name(), "spot");
  EXPECT_EQ(message->lights(3).name(), "bulb");
  EXPECT_TRUE(message->meshes(0).lights_from().empty());
  const glm::dvec3 sun_dir = glm::normalize(glm::dvec3(0.35, -1, 0.25));
  EXPECT_NEAR(glm::length(Vec3(message->lights(1).sun().direction()) - sun_dir), 0, 1e-6);
  const pdsm::v1::SpotLight& spot = message->lights(2).spot();
  EXPECT_NEAR(glm::length(Vec3(spot.center()) - glm::dvec3(-4 * 2 + 10, 12, 8)), 0, 1e-5);
  EXPECT_NEAR(spot.radius(), 0.6, 1e-12);
  EXPECT_NEAR(spot.cone_half_angle_deg(), 40.0, 1e-4);
  EXPECT_NEAR(glm::length(Vec3(message->lights(3).sphere().center()) - glm::dvec3(10, 6, 6)), 0,
              1e-5);
  EXPECT_NEAR(message->lights(3).sphere().radius(), 0.4, 1e-12);
  absl::StatusOr<Scene> scene = LoadSceneFile(scene_path);
  ASSERT_TRUE(scene.ok()) << scene.status();
  EXPECT_EQ(scene->LightCount(), 3u + kSphereFaceCount);

  // Only "file", only with a path; a message that still says so is not a scene file's.
  WriteText(scene_path, absl::StrCat(R"({"meshes": [{"path": ")", WorldPath(),
                                     R"(", "lightsFrom": "files"}]})"));
  absl::StatusOr<pdsm::v1::Scene> bad = ParseSceneFile(scene_path);
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.status().message().find(scene_path + ": meshes[0].lightsFrom: must be \"file\""),
            std::string::npos)
      << bad.status();
  WriteText(scene_path,
            R"({"meshes": [{"inline": {"positions": [0,0,0, 1,0,0, 0,0,1], "indices": [0,1,2]},)"
            R"( "lightsFrom": "file"}]})");
  bad = ParseSceneFile(scene_path);
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.status().message().find("needs the mesh's `path`"), std::string::npos)
      << bad.status();
  pdsm::v1::Scene sent = *message;
  sent.mutable_meshes(0)->set_lights_from("file");
  absl::StatusOr<Scene> remote = SceneFromProto(sent, "job 1", "");
  ASSERT_FALSE(remote.ok());
  EXPECT_NE(remote.status().message().find("meshes[0].lightsFrom"), std::string::npos)
      << remote.status();
}

TEST(WorldFile, AWorldWithoutALightToBakeIsRefusedNamingTheFile) {
  TempDir dir;
  const std::string obj = dir.File("plain.obj");
  WriteText(obj, "v 0 0 0\nv 1 0 0\nv 0 0 1\nf 1 2 3\n");
  absl::StatusOr<Scene> scene = LoadSceneFile(obj);
  ASSERT_FALSE(scene.ok());
  EXPECT_EQ(scene.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(scene.status().message().find(obj), std::string::npos) << scene.status();
  EXPECT_NE(scene.status().message().find("no light pdsm can bake"), std::string::npos)
      << scene.status();
  EXPECT_EQ(LoadSceneFile(dir.File("missing.gltf")).status().code(), absl::StatusCode::kNotFound);
}

TEST(WorldFile, ExtrasThatAreNotBakeFieldsAreRefusedNamingTheLight) {
  // The world with the spot's samples made 1.5 (a sample count is an integer).
  const std::string text = testing::ReadBytes(WorldPath());
  const size_t at = text.find("\"samples\": 32");
  ASSERT_NE(at, std::string::npos);
  std::string bad = text;
  bad.replace(at, 13, "\"samples\": 1.5");
  TempDir dir;
  const std::string path = dir.File("bad_extras.gltf");
  WriteText(path, bad);
  absl::StatusOr<Scene> scene = LoadSceneFile(path);
  ASSERT_FALSE(scene.ok());
  EXPECT_NE(scene.status().message().find("light \"spot\" extras"), std::string::npos)
      << scene.status();
}

}  // namespace
}  // namespace pdsm
