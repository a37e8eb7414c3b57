// Alpha-tested casters (issue #16 item 2): a card's texture decides where it casts, in the bake
// (the alpha-tested shadow-map program) and in the Embree reference (its hit filter) alike.
// The card world is tests/alpha_card.h's: seen from the light straight above, the card's
// shadow covers x < 0, and x >= 0 only for z < -2/3 (its texture's top rows).
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <glm/glm.hpp>

#include "core/pdsm/pdsm_file.h"
#include "core/pdsm/pdsm_query.h"
#include "core/reference/reference_attenuation.h"
#include "core/scene/scene_loader.h"
#include "tests/alpha_card.h"
#include "tests/test_support.h"
#include "worker/local_bake.h"

namespace pdsm {
namespace {

using testing::TempDir;

// Ground points and where the card's texture puts them (see above): the light (0.2 across,
// 3 above the card) blurs the edges by under 0.07, so every point is 0.15+ (three PDSM pixels)
// from an edge.
struct GroundPoint {
  glm::dvec3 p;
  bool behind_opaque_texels;  // in the shadow of the texture's opaque part
};
const std::vector<GroundPoint>& GroundPoints() {
  static const std::vector<GroundPoint> points = {
      {{-0.6, 0, 0.5}, true},   // under the opaque half (u < 1/2)
      {{-1.0, 0, -1.0}, true},  // the opaque half's far corner
      {{0.6, 0, 0.5}, false},   // under the clear half: the hole
      {{0.3, 0, -0.2}, false},  // the hole, near its top edge (card v 0.35)
      {{0.6, 0, -1.0}, true},   // under the top rows (v < 1/4), opaque across
      {{2.0, 0, 2.0}, false},   // beyond the card
  };
  return points;
}

// Bakes the card world written with `options`; returns the file's path.
std::string BakeCard(const TempDir& dir, const testing::AlphaCardOptions& options,
                     Scene* scene_out) {
  testing::WriteText(dir.File("card.gltf"), testing::AlphaCardGltf(options));
  testing::WriteText(dir.File("card.json"), testing::AlphaCardSceneJson("card.gltf", 128, 16));
  absl::StatusOr<Scene> scene = LoadSceneFile(dir.File("card.json"));
  EXPECT_TRUE(scene.ok()) << scene.status();
  if (!scene.ok()) return "";
  LocalBakeOptions bake;
  bake.output_path = dir.File("card.exr");
  bake.threads = 1;
  const absl::Status baked = RunLocalBake(*scene, bake).status();
  EXPECT_TRUE(baked.ok()) << baked;
  *scene_out = *std::move(scene);
  return baked.ok() ? bake.output_path : "";
}

TEST(AlphaTested, ACardsHoleLetsTheLightThroughInTheBakeAndTheReference) {
  TempDir dir;
  Scene scene;
  const std::string path = BakeCard(dir, {}, &scene);
  ASSERT_FALSE(path.empty());
  absl::StatusOr<PdsmImage> pdsm = ReadPdsm(path);
  ASSERT_TRUE(pdsm.ok()) << pdsm.status();
  std::vector<glm::dvec3> points;
  for (const GroundPoint& g : GroundPoints()) points.push_back(g.p);
  ReferenceOptions embree;  // auto: Embree, since the exact method has no alpha test
  embree.samples = 256;
  absl::StatusOr<std::vector<double>> reference = ReferenceAttenuation(scene, points, embree);
  ASSERT_TRUE(reference.ok()) << reference.status();
  for (size_t i = 0; i < points.size(); ++i) {
    const GroundPoint& g = GroundPoints()[i];
    SCOPED_TRACE(::testing::Message() << "ground point " << g.p.x << ", " << g.p.z);
    const double a = QueryAttenuation(*pdsm, g.p);
    if (g.behind_opaque_texels) {
      EXPECT_GE(a, 0.99);
      EXPECT_GE((*reference)[i], 0.99);
    } else {
      EXPECT_LE(a, 0.01);
      EXPECT_LE((*reference)[i], 0.01);
    }
  }
  // The exact reference refuses a scene it cannot see through.
  ReferenceOptions exact;
  exact.method = ReferenceMethod::kExact;
  EXPECT_EQ(ReferenceAttenuation(scene, points, exact).status().code(),
            absl::StatusCode::kUnimplemented);
}

TEST(AlphaTested, TheSameCardOpaqueCastsItsWholeSquare) {
  TempDir dir;
  testing::AlphaCardOptions opaque;
  opaque.alpha_mode = "OPAQUE";
  Scene scene;
  const std::string path = BakeCard(dir, opaque, &scene);
  ASSERT_FALSE(path.empty());
  absl::StatusOr<PdsmImage> pdsm = ReadPdsm(path);
  ASSERT_TRUE(pdsm.ok()) << pdsm.status();
  for (const GroundPoint& g : GroundPoints()) {
    const bool under_card = std::abs(g.p.x) < 1.2 && std::abs(g.p.z) < 1.2;
    EXPECT_EQ(QueryAttenuation(*pdsm, g.p) >= 0.99, under_card) << g.p.x << ", " << g.p.z;
  }
}

TEST(AlphaTested, AFaintMaskCastsNothing) {
  // The case: MASK with alpha 0.2 and no texture once cast a full umbra.
  TempDir dir;
  testing::AlphaCardOptions faint;
  faint.texture = false;
  faint.factor_alpha = 0.2;
  Scene scene;
  const std::string path = BakeCard(dir, faint, &scene);
  ASSERT_FALSE(path.empty());
  absl::StatusOr<PdsmImage> pdsm = ReadPdsm(path);
  ASSERT_TRUE(pdsm.ok()) << pdsm.status();
  for (const GroundPoint& g : GroundPoints()) {
    EXPECT_EQ(QueryAttenuation(*pdsm, g.p), 0.0) << g.p.x << ", " << g.p.z;
  }
}

TEST(AlphaTested, TheBakeIsTheSameForAnyThreadCount) {
  TempDir dir;
  Scene scene;
  const std::string path = BakeCard(dir, {}, &scene);
  ASSERT_FALSE(path.empty());
  const std::string one_thread = testing::ReadBytes(path);
  LocalBakeOptions bake;
  bake.output_path = dir.File("card2.exr");
  bake.threads = 2;
  ASSERT_TRUE(RunLocalBake(scene, bake).ok());
  EXPECT_TRUE(testing::ReadBytes(bake.output_path) == one_thread);
}

// The bundled foliage cards (examples/foliage, make_cards.py): light passes between the leaves.
// Ground points under the canopy's shadow are some lit, some shadowed, as the Embree reference
// says; opaque cards would leave the whole patch dark.
TEST(AlphaTested, TheBundledFoliageLetsLightBetweenItsLeaves) {
  pdsm::v1::BakeParams overrides;
  overrides.add_resolution(256);
  overrides.add_resolution(256);
  overrides.set_samples(16);
  const std::string path = std::string(PDSM_SOURCE_DIR) + "/examples/foliage/cards.gltf";
  std::vector<std::string> warnings;
  absl::StatusOr<Scene> scene = LoadSceneFile(path, overrides, &warnings);
  ASSERT_TRUE(scene.ok()) << scene.status();
  EXPECT_TRUE(warnings.empty()) << warnings[0];
  int masked_meshes = 0;
  for (const TriangleMesh& mesh : scene->meshes) masked_meshes += mesh.has_masks();
  EXPECT_EQ(masked_meshes, 1);
  TempDir dir;
  LocalBakeOptions bake;
  bake.output_path = dir.File("cards.exr");
  ASSERT_TRUE(RunLocalBake(*scene, bake).ok());
  absl::StatusOr<PdsmImage> pdsm = ReadPdsm(bake.output_path);
  ASSERT_TRUE(pdsm.ok()) << pdsm.status();
  // The canopy (around y 2.2..2.8, within ~1 of the trunk) falls along the sun's (0.3, 0.2)
  // per unit of height: about (0.75, 0.5) off the trunk.
  std::vector<glm::dvec3> points;
  for (double x = 0.1; x <= 1.5; x += 0.1) {
    for (double z = -0.3; z <= 1.3; z += 0.1) points.push_back({x, 0, z});
  }
  ReferenceOptions embree;
  embree.samples = 256;
  absl::StatusOr<std::vector<double>> reference = ReferenceAttenuation(*scene, points, embree);
  ASSERT_TRUE(reference.ok()) << reference.status();
  int lit = 0, dark = 0;
  double error = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    const double a = QueryAttenuation(*pdsm, points[i]);
    lit += a < 0.5;
    dark += a > 0.5;
    error += std::abs(a - (*reference)[i]);
  }
  const int n = static_cast<int>(points.size());
  EXPECT_GT(lit, n / 5) << "light between the leaves";
  EXPECT_GT(dark, n / 5) << "the leaves' shadows";
  EXPECT_LT(error / n, 0.05) << "mean |bake - Embree| over the patch";
}

}  // namespace
}  // namespace pdsm
