#include "core/bake/face_samples.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/bake/bake_plan.h"
#include "core/scene/scene.h"
#include "core/scene/sphere_faces.h"

namespace pdsm {
namespace {

// A sphere of radius 0.5 four units above a 20 x 20 ground with a caster plate between,
// baking its -y face (straight down) at 256^2 in 16-pixel tiles (0.125 of tangent each).
Scene FaceScene() {
  Scene scene;
  scene.name = "face_samples_test";
  scene.source_path = "face_samples_test.json";
  TriangleMesh ground;
  ground.label = "ground";
  ground.role = MeshRole::kReceiverOnly;
  ground.positions_world = {{-10, 0, -10}, {10, 0, -10}, {10, 0, 10}, {-10, 0, 10}};
  ground.indices = {0, 1, 2, 0, 2, 3};
  TriangleMesh plate;
  plate.label = "plate";
  plate.role = MeshRole::kCasterOnly;
  plate.positions_world = {{-1, 2, -1}, {1, 2, -1}, {1, 2, 1}, {-1, 2, 1}};
  plate.indices = {0, 1, 2, 0, 2, 3};
  scene.meshes = {ground, plate};
  scene.light = SphereFaceLight({0, 4, 0}, 0.5, SphereFaces()[3]);  // -y
  scene.light_name = "lamp@-y";
  scene.bake.width = scene.bake.height = 256;
  scene.bake.tile_size = 16;
  scene.bake.samples = 64;
  return scene;
}

TEST(FaceSamples, EachGroupSeesTheSpheresOutlineFromItsOwnDirection) {
  absl::StatusOr<BakePlan> plan = PlanBake(FaceScene());
  ASSERT_TRUE(plan.ok()) << plan.status();
  ASSERT_TRUE(IsSphereFacePlan(*plan));
  const PdsmGeometry& g = plan->geometry();
  const double stretch = FaceSampleStretch(*plan);
  EXPECT_GT(stretch, 1.0);
  // 1 / cos of the window's corner direction: the face's |s|, |t| <= 1 and the window's margin
  // (1e-3 of its width each side).
  EXPECT_LE(stretch, std::sqrt(1 + 2 * 1.002 * 1.002) + 1e-12);
  double radius = 0;
  for (const glm::dvec2& s : plan->samples) radius = std::max(radius, glm::length(s));
  EXPECT_LE(radius, 0.5 + 1e-12);
  ASSERT_GT(plan->group_count(), 4) << "a face's groups span at most kMaxFaceGroupTangent";
  for (int i = 0; i < plan->group_count(); ++i) {
    const TileGroup group = plan->group(i);
    // As wide as kMaxFaceGroupTangent allows, or one tile (a group has one at least).
    EXPECT_TRUE(group.width * g.PixelPitchS() <= kMaxFaceGroupTangent || group.tiles.size() == 1)
        << group.width * g.PixelPitchS();
    const double s = g.s_min + (group.x0 + 0.5 * group.width) * g.PixelPitchS();
    const double t = g.t_min + (group.y0 + 0.5 * group.height) * g.PixelPitchT();
    const glm::dvec3 w = glm::normalize(glm::dvec3(s, t, 1));
    const std::vector<glm::dvec2> samples = FaceGroupSamples(*plan, i);
    ASSERT_EQ(samples.size(), plan->samples.size());
    for (size_t k = 0; k < samples.size(); ++k) {
      // Seen along w (its part across w), each offset is the disk sample it came from: the
      // same distance from the centre, and the set is that disk turned to face w.
      const glm::dvec3 p(samples[k], 0.0);
      const glm::dvec3 across = p - glm::dot(p, w) * w;
      EXPECT_NEAR(glm::length(across), glm::length(plan->samples[k]), 1e-12);
      EXPECT_LE(glm::length(samples[k]), stretch * radius + 1e-12);
    }
    // Two samples' separation is kept too: the map is a rotation, not only a radial one.
    const glm::dvec3 p0(samples[0], 0.0), p1(samples[1], 0.0);
    const glm::dvec3 d = (p1 - p0) - glm::dot(p1 - p0, w) * w;
    EXPECT_NEAR(glm::length(d), glm::length(plan->samples[1] - plan->samples[0]), 1e-12);
  }
}

TEST(FaceSamples, OtherLightsKeepTheirSamples) {
  Scene scene = FaceScene();
  scene.light.face_tangent = 0;  // the same disk, not a face
  absl::StatusOr<BakePlan> plan = PlanBake(scene);
  ASSERT_TRUE(plan.ok()) << plan.status();
  EXPECT_FALSE(IsSphereFacePlan(*plan));
  EXPECT_EQ(FaceSampleStretch(*plan), 1.0);
}

}  // namespace
}  // namespace pdsm
