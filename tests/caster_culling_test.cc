// A light's plan keeps only the casters some tile can reach (BakePlan::casters_left_out,
// core/bake/caster_culling.h): a local light in a large world must not carry the world.
// Casters far outside the light's reach are left out of its plan, and the bake is byte for
// byte the bake of the scene without them; casters the light can see are all kept.
#include <array>
#include <set>
#include <string>

#include <gtest/gtest.h>

#include "absl/strings/str_cat.h"
#include "core/bake/bake_plan.h"
#include "core/scene/scene_loader.h"
#include "tests/test_support.h"
#include "worker/local_bake.h"

namespace pdsm::testing {
namespace {

// A 10 x 10 ground, a 1 x 1 x 1 box under a 1 x 1 rect light 4 above it, and (when `far`) a
// box of 12 triangles 200 units away that nothing of the light can see.
std::string Scene(bool far) {
  const std::string box = R"("positions": [-0.5,0.5,-0.5, 0.5,0.5,-0.5, 0.5,0.5,0.5, -0.5,0.5,0.5,
                                -0.5,1.5,-0.5, 0.5,1.5,-0.5, 0.5,1.5,0.5, -0.5,1.5,0.5],
                  "indices": [0,2,1, 0,3,2, 4,5,6, 4,6,7, 0,1,5, 0,5,4, 1,2,6, 1,6,5,
                              2,3,7, 2,7,6, 3,0,4, 3,4,7])";
  std::string meshes = absl::StrCat(
      R"({"inline": {"positions": [-5,0,-5, 5,0,-5, 5,0,5, -5,0,5], "indices": [0,1,2, 0,2,3]},
          "role": "RECEIVER_ONLY"},
         {"inline": {)",
      box, "}}");
  if (far) {
    absl::StrAppend(&meshes, R"(, {"inline": {)", box,
                    R"(}, "transform": [1,0,0,200, 0,1,0,0, 0,0,1,150, 0,0,0,1]})");
  }
  return absl::StrCat(R"({"name": "culling", "meshes": [)", meshes, R"(],
    "light": {"rect": {"center": [0.3,4,0.2], "normal": [0,-1,0], "up": [0,0,1], "size": [1,1]}},
    "bake": {"resolution": [64,64], "samples": 16, "tileSize": 16,
             "frustum": {"window": [-1.2,1.2,-1.2,1.2], "depthRange": [0.5, 5]}}})");
}

TEST(CasterCulling, FarCastersAreLeftOutAndTheBakeIsTheSceneWithoutThem) {
  TempDir dir;
  WriteText(dir.File("far.json"), Scene(true));
  WriteText(dir.File("near.json"), Scene(false));
  absl::StatusOr<pdsm::Scene> with_far = LoadSceneFile(dir.File("far.json"));
  absl::StatusOr<pdsm::Scene> without = LoadSceneFile(dir.File("near.json"));
  ASSERT_TRUE(with_far.ok() && without.ok()) << with_far.status() << without.status();
  absl::StatusOr<BakePlan> far_plan = PlanBake(*with_far);
  absl::StatusOr<BakePlan> near_plan = PlanBake(*without);
  ASSERT_TRUE(far_plan.ok() && near_plan.ok());
  EXPECT_EQ(far_plan->casters_left_out, 12u);  // the far box, whole
  EXPECT_EQ(near_plan->casters_left_out, 0u);  // the near box can shadow the ground: kept
  EXPECT_EQ(far_plan->casters.TriangleCount(), 12u);
  // The same triangles, by their vertices (their order follows the Morton curve over the
  // scene's bounds, which the far box widens: core/bake/scene_index.h).
  const auto triangles = [](const LightSpaceMesh& mesh) {
    std::set<std::array<float, 9>> out;
    for (size_t t = 0; t < mesh.TriangleCount(); ++t) {
      std::array<float, 9> key;
      for (int v = 0; v < 3; ++v) {
        const glm::vec3& p = mesh.positions[mesh.indices[3 * t + v]];
        key[3 * v] = p.x, key[3 * v + 1] = p.y, key[3 * v + 2] = p.z;
      }
      out.insert(key);
    }
    return out;
  };
  EXPECT_EQ(triangles(far_plan->casters), triangles(near_plan->casters));
  EXPECT_EQ(far_plan->casters.positions.size(), 8u);  // only the vertices the kept ones use

  for (const char* name : {"far", "near"}) {
    LocalBakeOptions options;
    options.output_path = dir.File(absl::StrCat(name, ".exr"));
    options.threads = 2;
    absl::StatusOr<BakeSummary> summary =
        RunLocalBake(std::string(name) == "far" ? *with_far : *without, options);
    ASSERT_TRUE(summary.ok()) << summary.status();
  }
  const std::string far_bytes = ReadBytes(dir.File("far.exr"));
  EXPECT_GT(far_bytes.size(), 1000u);
  EXPECT_EQ(far_bytes, ReadBytes(dir.File("near.exr")));
}

}  // namespace
}  // namespace pdsm::testing
