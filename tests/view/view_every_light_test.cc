// pdsm-view without --light on a scene and file of several lights shades with every light at
// once (issue #12 item 6): a sun, a rect lamp, a spot and a sphere bulb (several faces) over the
// courtyard. The fraction of the direct light hidden that the GPU shades with is checked, pixel
// by pixel on the ground, against the CPU: each light's attenuation from `pdsm query`'s code
// (the sphere's from the face PartAt picks), weighted by each light's direct term.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "client/view/frame_renderer.h"
#include "client/view/view_app.h"
#include "client/view/view_options.h"
#include "client/view/view_scene.h"
#include "core/pdsm/pdsm_file.h"
#include "core/pdsm/pdsm_lights.h"
#include "core/pdsm/pdsm_query.h"
#include "core/scene/scene_loader.h"
#include "gl/gl_functions.h"
#include "gl/platform/osmesa_context.h"
#include "tests/view/view_test_support.h"

namespace pdsm::testing {
namespace {

// The courtyard's meshes under its three lights and a sphere bulb, baked small.
constexpr char kScene[] = R"({
  "name": "courtyard_bulb",
  "meshes": [
    {"inline": {"positions": [-10,0,-10, 10,0,-10, 10,0,10, -10,0,10], "indices": [0,1,2, 0,2,3]},
     "role": "RECEIVER_ONLY"},
    {"inline": {"positions": [-1,0,-1, 1,0,-1, 1,0,1, -1,0,1], "indices": [0,1,2, 0,2,3]},
     "transform": [1.5,0,0,-1.5, 0,1,0,4, 0,0,1.5,-1, 0,0,0,1]},
    {"inline": {"positions": [-4,0,-0.15, 4,0,-0.15, 4,0,0.15, -4,0,0.15,
                              -4,0.3,-0.15, 4,0.3,-0.15, 4,0.3,0.15, -4,0.3,0.15],
                "indices": [0,1,2, 0,2,3, 4,6,5, 4,7,6, 0,4,5, 0,5,1, 3,2,6, 3,6,7]},
     "transform": [0.8660254,0,0.5,0, 0,1,0,1, -0.5,0,0.8660254,2.5, 0,0,0,1]}
  ],
  "lights": [
    {"name": "sun", "sun": {"direction": [0.3,-1,0.2], "angularDiameterDeg": 2}},
    {"name": "lamp", "rect": {"center": [0,10,0], "normal": [0,-1,0], "up": [0,0,1], "size": [3,3]}},
    {"name": "spot", "spot": {"center": [5,7,-5], "normal": [-0.5,-1,0.5], "radius": 0.5,
                              "coneHalfAngleDeg": 35}},
    {"name": "bulb", "sphere": {"center": [2,2.5,2], "radius": 0.3}}
  ],
  "bake": {"resolution": [64,64], "samples": 16, "shadowMapResolution": 256, "tileSize": 32,
           "epsilon": 0.01}
})";

// A light's direct term at a point of normal `n` (world), as shade.frag computes it: Lambert
// toward the light's centre, times the emitter's cosine for a planar light.
double Direct(const PdsmHeader& h, const glm::dvec3& p_world, const glm::dvec3& n_world) {
  const LightFrame& f = h.geometry.frame;
  const glm::dvec3 q = f.LightFromWorld(p_world);
  const glm::dvec3 n(glm::dot(f.u, n_world), glm::dot(f.v, n_world), glm::dot(f.n, n_world));
  const bool ortho = h.geometry.projection == Projection::kOrthographic;
  const glm::dvec3 to_light = ortho ? glm::dvec3(0, 0, -1) : glm::normalize(-q);
  const bool planar = !ortho && h.face_tangent == 0;
  return std::max(glm::dot(n, to_light), 0.0) * (planar ? std::max(-to_light.z, 0.0) : 1.0);
}

TEST(ViewEveryLight, TheHiddenFractionIsEveryLightsAttenuationWeightedByItsDirectLight) {
  TempDir dir;
  const std::string scene_path = dir.File("scene.json");
  WriteText(scene_path, kScene);
  absl::StatusOr<Scene> scene = LoadSceneFile(scene_path);
  ASSERT_TRUE(scene.ok()) << scene.status();
  LocalBakeOptions bake;
  bake.output_path = dir.File("court.exr");
  ASSERT_TRUE(RunLocalBake(*scene, bake).ok());

  view::ViewOptions options;
  options.scene_path = scene_path;
  options.pdsm_path = bake.output_path;
  options.headless = true;
  absl::StatusOr<view::ViewScene> view = view::LoadViewScene(options);
  ASSERT_TRUE(view.ok()) << view.status();
  absl::StatusOr<PdsmReader> reader = PdsmReader::Open(bake.output_path);
  ASSERT_TRUE(reader.ok());
  const std::vector<PdsmHeader>& headers = reader->headers();
  const std::vector<PdsmLightParts> lights = LightsOfParts(headers);
  ASSERT_EQ(lights.size(), 4u);
  ASSERT_GT(lights[3].parts.size(), 1u);  // the bulb's faces
  ASSERT_EQ(view->every_light.size(), headers.size());
  std::vector<PdsmImage> parts;
  for (int p = 0; p < reader->light_count(); ++p) {
    absl::StatusOr<PdsmImage> image = reader->ReadLight(p);
    ASSERT_TRUE(image.ok());
    parts.push_back(*std::move(image));
  }

  absl::StatusOr<gl::OsMesaContext> context = gl::OsMesaContext::Create();
  ASSERT_TRUE(context.ok()) << context.status();
  absl::StatusOr<gl::GlFunctions> gl = gl::GlFunctions::Load(&gl::OsMesaContext::GetProcAddress);
  ASSERT_TRUE(gl.ok());
  std::vector<float> hidden, positions;
  {
    absl::StatusOr<std::unique_ptr<view::FrameRenderer>> r =
        view::FrameRenderer::Create(*gl, &*view, view::RenderSettings{});
    ASSERT_TRUE(r.ok()) << r.status();
    const view::Camera camera{{0, 16, 9}, {0, 0, 0}, 60};
    ASSERT_TRUE((*r)->Render(view::ViewMode::kPdsm, camera, 240, 180).ok());
    absl::StatusOr<view::Frame> frame = (*r)->ReadFrame();
    ASSERT_TRUE(frame.ok());
    hidden = frame->attenuation;
    absl::StatusOr<std::vector<float>> p = (*r)->ReadPositions(camera, 240, 180);
    ASSERT_TRUE(p.ok());
    positions = *std::move(p);
  }

  const LightFrame& view_frame = view->frame();
  int ground = 0, off = 0, partial = 0, first_light_only_differs = 0;
  std::set<int> faces;
  std::vector<int> shadowed_by(lights.size(), 0);
  double worst = 0;
  for (size_t i = 0; i < hidden.size(); ++i) {
    if (positions[4 * i + 3] == 0) continue;
    const glm::dvec3 p = view_frame.WorldFromLight(
        glm::dvec3(positions[4 * i], positions[4 * i + 1], positions[4 * i + 2]));
    if (std::abs(p.y) > 1e-4 || std::abs(p.x) > 9.9 || std::abs(p.z) > 9.9) continue;
    const glm::dvec3 n(0, 1, 0);  // the ground, seen from above
    double arrives = 0, total = 0;
    for (size_t l = 0; l < lights.size(); ++l) {
      const int part = PartAt(headers, lights[l], p);
      if (l == 3) faces.insert(part);
      double a = QueryAttenuation(parts[part], p);
      if (std::isnan(a)) a = 0;  // outside its frustum: lit
      shadowed_by[l] += a > 0.5;
      const double d = Direct(headers[part], p, n);
      arrives += d * (1 - a);
      total += d;
    }
    const double expected = total > 0 ? 1 - arrives / total : 0;
    ++ground;
    partial += expected > 0.05 && expected < 0.95;
    const double error = std::abs(hidden[i] - expected);
    worst = std::max(worst, error);
    off += error > 1e-4;
    double a0 = QueryAttenuation(parts[0], p);
    first_light_only_differs += std::abs((std::isnan(a0) ? 0 : a0) - expected) > 0.05;
  }
  std::printf(
      "%d ground pixels, %d partly hidden, %d more than 1e-4 off (worst %.2g); bulb "
      "faces used %zu; shadowed (A > 0.5) by sun %d, lamp %d, spot %d, bulb %d\n",
      ground, partial, off, worst, faces.size(), shadowed_by[0], shadowed_by[1], shadowed_by[2],
      shadowed_by[3]);
  EXPECT_GT(ground, 10000);
  EXPECT_GT(partial, 500);
  EXPECT_LE(off, ground / 1000);  // fragments on a jump, as in ViewAgreement
  EXPECT_GE(faces.size(), 2u);
  for (size_t l = 0; l < lights.size(); ++l) EXPECT_GT(shadowed_by[l], 20) << "light " << l;
  EXPECT_GT(first_light_only_differs, 1000);  // the other lights are really shaded
}

// The comparison modes shade one light: without --light they are refused, naming the flag.
TEST(ViewEveryLight, OtherModesNeedALightNamed) {
  TempDir dir;
  const std::string scene_path = ExamplePath("courtyard");
  absl::StatusOr<Scene> scene = LoadSceneFile(scene_path);
  ASSERT_TRUE(scene.ok());
  CommandResult r =
      RunCommand(std::string(PDSM_VIEW) + " " + scene_path + " --pdsm " + SmallBake("courtyard") +
                     " --headless --mode hard" + " --screenshot " + dir.File("x.png"),
                 dir);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--light"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir.File("x.png")));
  r = RunCommand(std::string(PDSM_VIEW) + " " + scene_path + " --pdsm " + SmallBake("courtyard") +
                     " --headless --mode hard --light lamp --screenshot " + dir.File("y.png"),
                 dir);
  EXPECT_EQ(r.exit_code, 0) << r.err;
}

}  // namespace
}  // namespace pdsm::testing
