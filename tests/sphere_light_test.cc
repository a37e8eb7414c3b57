// A sphere light (core/scene/sphere_faces.h) bakes as six faces, one part each, and reads back
// as one light: every direction around it is answered by the face that holds it, umbrae read 1
// and lit points 0, and the faces' disk approximation stays within its measured error of the
// Embree reference that samples the true sphere (docs/scene_format.md, "Sphere lights").
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "core/pdsm/pdsm_file.h"
#include "core/pdsm/pdsm_lights.h"
#include "core/pdsm/pdsm_tile_cache.h"
#include "core/reference/reference_attenuation.h"
#include "core/scene/scene_loader.h"
#include "core/scene/sphere_faces.h"
#include "tests/test_support.h"
#include "worker/local_bake.h"

namespace pdsm {
namespace {

using testing::CommandResult;
using ::testing::HasSubstr;
using testing::RunCommand;
using testing::TempDir;

// A 2 x 2 caster plate at height 2 over a 16 x 16 receiver floor, a 1 x 2 wall standing at
// x = 4 (its shadow falls in the +x face), and a sphere of radius 0.3 at (0.5, 4, 0).
std::string WriteSphereScene(const TempDir& dir, const std::string& bake) {
  const std::string path = dir.File("sphere.json");
  testing::WriteText(
      path, absl::StrCat(
                R"({"name": "bulb", "meshes": [)",
                R"({"inline": {"positions": [-8,0,-8, 8,0,-8, 8,0,8, -8,0,8],)",
                R"( "indices": [0,1,2, 0,2,3]}, "role": "RECEIVER_ONLY"},)",
                R"( {"inline": {"positions": [-1,2,-1, 1,2,-1, 1,2,1, -1,2,1],)",
                R"( "indices": [0,1,2, 0,2,3]}, "role": "CASTER_ONLY"},)",
                R"( {"inline": {"positions": [4,0,-1, 4,0,1, 4,2,1, 4,2,-1],)",
                R"( "indices": [0,1,2, 0,2,3]}, "role": "CASTER_ONLY"}],)",
                R"( "lights": [{"name": "lamp", "sphere": {"center": [0.5,4,0], "radius": 0.3}}],)",
                R"( "bake": )", bake, "}"));
  return path;
}

TEST(SphereLight, LoadsAsSixFacesNamedAfterTheLight) {
  TempDir dir;
  absl::StatusOr<Scene> scene = LoadSceneFile(WriteSphereScene(dir, "{}"));
  ASSERT_TRUE(scene.ok()) << scene.status();
  ASSERT_EQ(scene->LightCount(), size_t{kSphereFaceCount});
  for (size_t i = 0; i < scene->LightCount(); ++i) {
    const SceneLight light = LightOf(*scene, i);
    EXPECT_EQ(light.name, absl::StrCat("lamp@", SphereFaces()[i].label));
    EXPECT_EQ(SphereOfFace(light.name), "lamp");
    EXPECT_EQ(light.spec.shape, LightShape::kDisk);
    EXPECT_DOUBLE_EQ(light.spec.radius, 0.3);
    EXPECT_EQ(light.spec.frame.center, glm::dvec3(0.5, 4, 0));
    EXPECT_EQ(light.spec.frame.n, SphereFaces()[i].axis);
    EXPECT_NEAR(glm::dot(glm::cross(light.spec.frame.u, light.spec.frame.v), light.spec.frame.n),
                1.0, 1e-15);
    EXPECT_EQ(light.spec.face_tangent, kSphereFaceTangent);
  }
  // Errors name the sphere's fields; a frustum cannot be shared by six faces.
  const std::string bad = dir.File("bad.json");
  testing::WriteText(bad, R"({"lights": [{"name": "a", "disk": {"center": [0,1,0],
      "normal": [0,-1,0], "radius": 1}}, {"name": "b", "sphere": {"center": [0,1,0],
      "radius": -1}}]})");
  absl::StatusOr<Scene> refused = LoadSceneFile(bad);
  ASSERT_FALSE(refused.ok());
  EXPECT_THAT(refused.status().message(), HasSubstr("lights[1].sphere.radius"));
  testing::WriteText(bad, R"({"light": {"sphere": {"center": [0,1,0], "radius": 1}},
      "bake": {"frustum": {"window": [-1,1,-1,1], "depthRange": [1,2]}}})");
  refused = LoadSceneFile(bad);
  ASSERT_FALSE(refused.ok());
  EXPECT_THAT(refused.status().message(), HasSubstr("bake.frustum"));
  // An unnamed sphere (the one-light form) gets a name for its faces.
  testing::WriteText(bad, R"({"light": {"sphere": {"center": [0,1,0], "radius": 1}}})");
  absl::StatusOr<Scene> unnamed = LoadSceneFile(bad);
  ASSERT_TRUE(unnamed.ok()) << unnamed.status();
  EXPECT_EQ(unnamed->light_name, "sphere@+x");
}

TEST(SphereLight, ReadsBackAsOneLightAnsweredByTheFaceThatHoldsEachPoint) {
  TempDir dir;
  absl::StatusOr<Scene> scene = LoadSceneFile(WriteSphereScene(
      dir, R"({"resolution": [128, 128], "samples": 64, "tileSize": 32, "epsilon": 0.005})"));
  ASSERT_TRUE(scene.ok()) << scene.status();
  LocalBakeOptions options;
  options.output_path = dir.File("sphere.exr");
  ASSERT_TRUE(RunLocalBake(*scene, options).ok());
  absl::StatusOr<PdsmReader> reader = PdsmReader::Open(options.output_path);
  ASSERT_TRUE(reader.ok()) << reader.status();
  ASSERT_EQ(reader->light_count(), kSphereFaceCount);
  const std::vector<PdsmLightParts> lights = LightsOfParts(reader->headers());
  ASSERT_EQ(lights.size(), 1u);
  EXPECT_EQ(lights[0].name, "lamp");
  EXPECT_EQ(lights[0].parts.size(), size_t{kSphereFaceCount});
  for (const PdsmHeader& h : reader->headers()) EXPECT_EQ(h.face_tangent, kSphereFaceTangent);
  // A face named alone is one part; a name that is neither says what there is.
  absl::StatusOr<PdsmLightParts> face =
      FindLightParts(reader->headers(), options.output_path, "lamp@-y");
  ASSERT_TRUE(face.ok()) << face.status();
  EXPECT_EQ(face->parts, std::vector<int>{3});
  EXPECT_THAT(FindLightParts(reader->headers(), options.output_path, "moon").status().message(),
              HasSubstr("its lights: \"lamp\""));

  // The floor, seen from the sphere through its -y face (straight below) and its four side
  // faces (beyond 45 degrees off the vertical), and a band above the plate.
  std::vector<glm::dvec3> points;
  for (double x = -7.5; x <= 7.5; x += 0.125) {
    for (double z = -7.5; z <= 7.5; z += 0.5) points.emplace_back(x, 0, z);
  }
  for (double x = -0.9; x <= 0.9; x += 0.3) points.emplace_back(x, 3, 0.1);
  PdsmTileCache cache(*std::move(reader), 64 << 20);
  absl::StatusOr<std::vector<double>> baked = AttenuationAt(cache, lights, points);
  ASSERT_TRUE(baked.ok()) << baked.status();
  ReferenceOptions embree;
  embree.samples = 4096;
  absl::StatusOr<std::vector<double>> reference = ReferenceAttenuation(*scene, points, embree);
  ASSERT_TRUE(reference.ok()) << reference.status();

  double error = 0, penumbra_error = 0, worst = 0;
  glm::dvec3 worst_at(0.0);
  int penumbra = 0, side_faces = 0, umbra = 0, lit = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    const double a = (*baked)[i];
    ASSERT_FALSE(std::isnan(a)) << "no face answers at " << points[i].x << "," << points[i].y << ","
                                << points[i].z;
    const double ref = (*reference)[i];
    ASSERT_FALSE(std::isnan(ref));
    const double e = std::abs(a - ref);
    error += e / points.size();
    if (e > worst) {
      worst = e;
      worst_at = points[i];
    }
    if (ref > 0.02 && ref < 0.98) {
      penumbra_error += e;
      ++penumbra;
    }
    const glm::dvec3 d = points[i] - glm::dvec3(0.5, 4, 0);
    side_faces += std::max(std::abs(d.x), std::abs(d.z)) > std::abs(d.y);
    // Exact plateaus: the plate's umbra (its shadow x in [-2.5, 1.5], z in [-2, 2], less the
    // penumbrae, 0.3 wide, and a pixel) reads 1, the floor far from every shadow 0.
    if (points[i].y == 0 && points[i].x > -1.9 && points[i].x < 0.9 &&
        std::abs(points[i].z) < 1.4) {
      EXPECT_EQ(ref, 1.0);
      EXPECT_EQ(a, 1.0) << points[i].x << "," << points[i].z;
      ++umbra;
    }
    if (points[i].y == 0 && std::abs(points[i].z) >= 3) {
      EXPECT_EQ(ref, 0.0);
      EXPECT_EQ(a, 0.0) << points[i].x << "," << points[i].z;
      ++lit;
    }
  }
  EXPECT_GT(side_faces, 1000) << "the floor beyond 45 degrees is the side faces'";
  EXPECT_GT(umbra, 50);
  EXPECT_GT(lit, 500);
  ASSERT_GT(penumbra, 50);
  penumbra_error /= penumbra;
  // Measured: mean 0.0007, penumbra mean 0.0080 (204 points), worst 0.245 at (4.125, 0, 1), the
  // wall's foot (a contact narrower than a pixel: issue #15, not the faces). Each face's disk
  // alone, without its groups turning it (core/bake/face_samples.h), measured 0.0012 and 0.018.
  // Bounds with room for the reference's own noise (0.5 / sqrt(4096) = 0.008 per point at most).
  EXPECT_LT(error, 0.002);
  EXPECT_LT(penumbra_error, 0.013);
  EXPECT_LT(worst, 0.3);
  std::printf("sphere: mean %.4f, penumbra mean %.4f (%d points), worst %.3f at (%g, %g, %g)\n",
              error, penumbra_error, penumbra, worst, worst_at.x, worst_at.y, worst_at.z);
}

TEST(SphereLight, SameBytesForAnyThreadsAndBatches) {
  TempDir dir;
  absl::StatusOr<Scene> scene = LoadSceneFile(
      WriteSphereScene(dir, R"({"resolution": [128, 128], "samples": 24, "tileSize": 32})"));
  ASSERT_TRUE(scene.ok()) << scene.status();
  LocalBakeOptions options;
  options.output_path = dir.File("a.exr");
  options.threads = 2;
  ASSERT_TRUE(RunLocalBake(*scene, options).ok());
  options.output_path = dir.File("b.exr");
  options.threads = 1;
  options.samples_per_task = 5;
  ASSERT_TRUE(RunLocalBake(*scene, options).ok());
  EXPECT_EQ(testing::ReadBytes(dir.File("a.exr")), testing::ReadBytes(dir.File("b.exr")));
}

TEST(SphereLight, CommandsTakeTheSphereByItsNameAndEachFaceByItsOwn) {
  TempDir dir;
  const std::string scene =
      WriteSphereScene(dir, R"({"resolution": [64, 64], "samples": 16, "tileSize": 32})");
  const std::string out = dir.File("s.exr");
  const std::string cli = PDSM_CLI;
  CommandResult bake =
      RunCommand(absl::StrCat(cli, " bake ", scene, " -o ", out, " --no-preview"), dir);
  ASSERT_EQ(bake.exit_code, 0) << bake.err;
  EXPECT_THAT(bake.err, ::testing::Not(HasSubstr("outside"))) << "a face's reach is bounded";
  EXPECT_THAT(bake.out, HasSubstr("1 light in 6 parts"));
  const std::string points = dir.File("p.csv");
  testing::WriteText(points, "0,0,0\n7,0,0\n0.5,3,0\n");
  CommandResult all = RunCommand(absl::StrCat(cli, " query ", out, " --points ", points), dir);
  ASSERT_EQ(all.exit_code, 0) << all.err;
  const std::vector<std::string> lines = absl::StrSplit(all.out, '\n', absl::SkipEmpty());
  ASSERT_EQ(lines.size(), 3u) << all.out;
  EXPECT_EQ(lines[0], "0,0,0,1.000000") << "under the plate: one column, the sphere's";
  EXPECT_EQ(lines[2], "0.5,3,0,0.000000");
  CommandResult named =
      RunCommand(absl::StrCat(cli, " query ", out, " --points ", points, " --light lamp"), dir);
  ASSERT_EQ(named.exit_code, 0) << named.err;
  EXPECT_EQ(named.out, all.out);
  // 7,0,0 lies in the +x face: that face alone answers the same; the -y face has no answer.
  testing::WriteText(points, "7,0,0\n");
  CommandResult px =
      RunCommand(absl::StrCat(cli, " query ", out, " --points ", points, " --light lamp@+x"), dir);
  ASSERT_EQ(px.exit_code, 0) << px.err;
  EXPECT_EQ(px.out, lines[1] + "\n");
  CommandResult my =
      RunCommand(absl::StrCat(cli, " query ", out, " --points ", points, " --light lamp@-y"), dir);
  ASSERT_EQ(my.exit_code, 0) << my.err;
  EXPECT_EQ(my.out, "7,0,0,nan\n");
  CommandResult info = RunCommand(absl::StrCat(cli, " info ", out), dir);
  ASSERT_EQ(info.exit_code, 0) << info.err;
  EXPECT_THAT(info.out, HasSubstr("1 light in 6 parts"));
  EXPECT_THAT(info.out, HasSubstr("light \"lamp@-z\""));
  EXPECT_THAT(info.out, HasSubstr("sphere-face"));
  CommandResult info_sphere = RunCommand(absl::StrCat(cli, " info ", out, " --light lamp"), dir);
  ASSERT_EQ(info_sphere.exit_code, 0) << info_sphere.err;
  EXPECT_EQ(info_sphere.out, info.out) << "the sphere by its name is its six faces";
  // The reference of a one-sphere scene is the sphere's, at every point.
  testing::WriteText(points, "0,0,0\n7,0,0\n0.5,3,0\n");
  CommandResult reference =
      RunCommand(absl::StrCat(cli, " reference ", scene, " --points ", points), dir);
  ASSERT_EQ(reference.exit_code, 0) << reference.err;
  const std::vector<std::string> ref_lines = absl::StrSplit(reference.out, '\n', absl::SkipEmpty());
  ASSERT_EQ(ref_lines.size(), 3u) << reference.out;
  EXPECT_EQ(ref_lines[0], "0,0,0,1.000000");
  EXPECT_EQ(ref_lines[2], "0.5,3,0,0.000000");
}

}  // namespace
}  // namespace pdsm
