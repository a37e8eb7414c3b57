// The viewer's pure pieces: flags, camera, the scene/PDSM match check, the shadow-map
// projections (against DESIGN.md's formulas, on random points).
#include <random>

#include <gtest/gtest.h>

#include "client/view/camera.h"
#include "client/view/shadow_maps.h"
#include "client/view/text_overlay.h"
#include "client/view/view_app.h"
#include "client/view/view_mode.h"
#include "client/view/view_scene.h"
#include "core/pdsm/pdsm_file.h"
#include "core/scene/scene_loader.h"
#include "tests/test_support.h"
#include "tests/view/view_test_support.h"

namespace pdsm::testing {
namespace {

TEST(ViewUnits, ModeListsRoundTripAndNameTheBadEntry) {
  absl::StatusOr<std::vector<view::ViewMode>> all =
      view::ParseModeList("pdsm,cpu,hard,pcf,pcss,vsm,multi-sm", "--compare");
  ASSERT_TRUE(all.ok()) << all.status();
  ASSERT_EQ(all->size(), std::size(view::kAllModes));
  for (size_t i = 0; i < all->size(); ++i) EXPECT_EQ((*all)[i], view::kAllModes[i]);
  absl::StatusOr<std::vector<view::ViewMode>> bad = view::ParseModeList("pdsm,soft", "--compare");
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.status().message().find("--compare"), std::string::npos);
  EXPECT_NE(bad.status().message().find("soft"), std::string::npos);
}

// --compare's layout: up to 4 per row, as few spare cells as can be.
TEST(ViewUnits, CompareColumnsLeaveFewSpareCells) {
  for (auto [tiles, columns] :
       {std::pair{1, 1}, {2, 2}, {3, 3}, {4, 4}, {5, 3}, {6, 3}, {7, 4}, {8, 4}, {9, 3}, {10, 4}}) {
    EXPECT_EQ(view::CompareColumns(tiles), columns) << tiles;
  }
}

// Labels change only the pixels of their box, and a label of other text looks different.
TEST(ViewUnits, LabelsDrawTextInTheirBoxOnly) {
  view::RgbImage a{60, 30, std::vector<uint8_t>(60 * 30 * 3, 128)};
  view::RgbImage b = a;
  view::DrawLabel(&a, 2, 3, "PDSM", 1);
  view::DrawLabel(&b, 2, 3, "HARD", 1);
  const int box_w = view::TextWidth("PDSM", 1) + 4, box_h = view::TextHeight(1) + 4;
  int white = 0, differing = 0;
  for (int y = 0; y < 30; ++y) {
    for (int x = 0; x < 60; ++x) {
      const size_t p = (static_cast<size_t>(y) * 60 + x) * 3;
      const bool in_box = x >= 2 && x < 2 + box_w && y >= 3 && y < 3 + box_h;
      if (!in_box) {
        EXPECT_EQ(a.rgb[p], 128) << x << "," << y;
      }
      white += a.rgb[p] == 255;
      differing += a.rgb[p] != b.rgb[p];
    }
  }
  EXPECT_GT(white, 30);
  EXPECT_GT(differing, 10);
  EXPECT_EQ(view::LabelScale(120), 1);
  EXPECT_EQ(view::LabelScale(720), 5);
}

// The default camera frames the casters and the shadows they throw: a shadowed ground point
// well outside the casters' bounds is inside the framing, and in view.
TEST(ViewUnits, DefaultCameraFramesTheShadowsToo) {
  view::ViewScene scene;
  absl::StatusOr<Scene> plates = LoadSceneFile(ExamplePath("plates"));
  absl::StatusOr<PdsmImage> pdsm = ReadPdsm(SmallBake("plates"));
  ASSERT_TRUE(plates.ok() && pdsm.ok());
  scene.scene = *plates;
  scene.pdsm = view::PdsmTiles::FromImage(*pdsm);
  view::PrepareViewScene(&scene);
  glm::dvec3 lo, hi;
  view::DefaultFraming(scene, &lo, &hi);
  // The square (x in [-3, 0], z in [-2.5, 0.5] at y = 4) throws its shadow beyond the casters'
  // bounds towards -x, -z (the light is at the origin's vertical, 10 up).
  EXPECT_LT(lo.x, scene.casters_min_world.x - 0.5);
  EXPECT_LT(lo.z, scene.casters_min_world.z - 0.5);
  EXPECT_LT(lo.y, scene.casters_min_world.y + 0.01);  // the ground is in
  EXPECT_LT(hi.x - lo.x, 20.0);                       // not the whole 20 x 20 ground
  // Every corner of the framing projects inside the image.
  const view::Camera camera = view::DefaultCamera(scene, 16.0 / 9.0);
  const glm::mat4 clip = view::ClipFromLight(camera, scene, 16.0 / 9.0);
  for (int c = 0; c < 8; ++c) {
    const glm::dvec3 w((c & 1) ? hi.x : lo.x, (c & 2) ? hi.y : lo.y, (c & 4) ? hi.z : lo.z);
    const glm::vec4 p = clip * glm::vec4(glm::vec3(scene.frame().LightFromWorld(w)), 1.0f);
    EXPECT_LE(std::abs(p.x / p.w), 1.0f) << c;
    EXPECT_LE(std::abs(p.y / p.w), 1.0f) << c;
  }
}

TEST(ViewUnits, CameraParsesAndRefusesNonsense) {
  absl::StatusOr<view::Camera> c = view::ParseCamera("1,2,3,4,5,6,30", "--camera");
  ASSERT_TRUE(c.ok()) << c.status();
  EXPECT_EQ(c->eye_world, glm::dvec3(1, 2, 3));
  EXPECT_EQ(c->target_world, glm::dvec3(4, 5, 6));
  EXPECT_EQ(c->fov_y_degrees, 30);
  absl::StatusOr<view::Camera> again = view::ParseCamera(view::FormatCamera(*c), "--camera");
  ASSERT_TRUE(again.ok());
  EXPECT_EQ(again->eye_world, c->eye_world);
  for (const char* bad : {"1,2,3", "1,2,3,1,2,3", "1,2,3,4,5,nan", "1,2,3,4,5,6,179", "a,b"}) {
    EXPECT_FALSE(view::ParseCamera(bad, "--camera").ok()) << bad;
  }
}

// A camera orbited in any direction keeps its distance and never flips over the pole.
TEST(ViewUnits, OrbitKeepsDistanceAndStaysOffThePole) {
  view::Camera c;
  c.eye_world = {3, 4, 5};
  c.target_world = {1, 1, 1};
  const double distance = glm::length(c.eye_world - c.target_world);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> angle(-1.0, 1.0);
  for (int i = 0; i < 200; ++i) {
    view::Orbit(&c, angle(rng), angle(rng));
    EXPECT_NEAR(glm::length(c.eye_world - c.target_world), distance, 1e-9);
    const glm::dvec3 dir = glm::normalize(c.eye_world - c.target_world);
    EXPECT_LT(std::abs(dir.y), 0.9951);
  }
}

// ShadowClipFromLight maps a light-space point to the window position DESIGN.md gives for the
// sample ((x - a) / z perspective, x - a z sun), and keeps depth order (reversed: nearer is
// larger) over the bake's depth range.
TEST(ViewUnits, ShadowMapProjectionFollowsTheBakeGeometry) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (Projection projection : {Projection::kPerspective, Projection::kOrthographic}) {
    PdsmHeader header;
    header.geometry.projection = projection;
    header.geometry.s_min = -0.7, header.geometry.s_max = 0.5;
    header.geometry.t_min = -0.4, header.geometry.t_max = 0.9;
    header.geometry.z_near = 2, header.geometry.z_far = 20;
    header.light_half_width = 1.5, header.light_half_height = 0.5;
    header.tan_half_angle = 0.02;
    header.light_shape =
        projection == Projection::kPerspective ? LightShape::kRect : LightShape::kSun;
    const view::ShadowMapLayout layout = view::MakeShadowMapLayout(header, 256, true);
    for (int i = 0; i < 500; ++i) {
      const glm::dvec2 sample(unit(rng) * 0.02, unit(rng) * 0.02);
      const glm::dvec3 p(unit(rng) * 3, unit(rng) * 3, 2 + 18 * (0.5 + 0.5 * unit(rng)));
      const glm::dvec2 st = projection == Projection::kPerspective ? (glm::dvec2(p) - sample) / p.z
                                                                   : glm::dvec2(p) - sample * p.z;
      const glm::dvec2 expected_ndc = 2.0 * (st - layout.window_min) / layout.window_size - 1.0;
      const glm::vec4 clip = view::ShadowClipFromLight(header, layout, sample) * glm::vec4(p, 1);
      EXPECT_NEAR(clip.x / clip.w, expected_ndc.x, 1e-4);
      EXPECT_NEAR(clip.y / clip.w, expected_ndc.y, 1e-4);
      const float depth = clip.z / clip.w;
      EXPECT_GT(depth, 0.0f);
      EXPECT_LT(depth, 1.0f);
      const glm::vec4 farther =
          view::ShadowClipFromLight(header, layout, sample) * glm::vec4(p + glm::dvec3(0, 0, 1), 1);
      EXPECT_LT(farther.z / farther.w, depth);
    }
  }
}

TEST(ViewUnits, MatchCheckNamesTheDifferingHeaderField) {
  absl::StatusOr<Scene> scene = LoadSceneFile(ExamplePath("plates"));
  ASSERT_TRUE(scene.ok()) << scene.status();
  PdsmHeader header;
  header.scene_name = scene->name;
  header.light_shape = scene->light.shape;
  header.geometry.frame = scene->light.frame;
  header.light_half_width = scene->light.half_width;
  header.light_half_height = scene->light.half_height;
  EXPECT_TRUE(view::CheckPdsmMatchesScene(*scene, header, "p.exr").ok());
  const auto expect_field = [&](PdsmHeader h, const std::string& field) {
    absl::Status s = view::CheckPdsmMatchesScene(*scene, h, "p.exr");
    EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument) << field;
    EXPECT_NE(s.message().find(field), std::string::npos) << s.message();
    EXPECT_NE(s.message().find("p.exr"), std::string::npos) << s.message();
  };
  PdsmHeader h = header;
  h.scene_name = "other";
  expect_field(h, "scene_name");
  h = header;
  h.geometry.frame.center.x += 0.5;
  expect_field(h, "light centre");
  h = header;
  h.geometry.frame.n = -h.geometry.frame.n;
  expect_field(h, "light normal");
  h = header;
  h.light_half_height *= 1.1;
  expect_field(h, "light size");
  h = header;
  h.light_shape = LightShape::kDisk;
  expect_field(h, "light_shape");
}

}  // namespace
}  // namespace pdsm::testing
