// Adaptive resolution end to end (issue #15 item 2; docs/algorithms.md section 10): a box on a
// plane baked with and without bake.maxRefinement, read back and compared with the exact
// reference and with each other. The contact beside the box's lit wall is the case the issue
// names: unrefined, ground under the box within a pixel of the wall blends with the lit ray
// beside it (ContactAccuracy in bake_accuracy_test.cc).
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/pdsm/pdsm_file.h"
#include "core/pdsm/pdsm_query.h"
#include "core/pdsm/refined_pixel.h"
#include "core/reference/exact_visibility.h"
#include "core/scene/scene_loader.h"
#include "tests/box_on_plane.h"
#include "tests/test_support.h"
#include "worker/local_bake.h"

namespace pdsm {
namespace {

using testing::kBoxOnPlaneJson;
using testing::ReadBytes;
using testing::TempDir;
using testing::WriteText;

Scene LoadBox(const TempDir& dir, const pdsm::v1::BakeParams& overrides) {
  const std::string path = dir.File("box_on_plane.json");
  WriteText(path, kBoxOnPlaneJson);
  absl::StatusOr<Scene> scene = LoadSceneFile(path, overrides);
  EXPECT_TRUE(scene.ok()) << scene.status();
  return scene.ok() ? *std::move(scene) : Scene{};
}

pdsm::v1::BakeParams Refined(int max_refinement) {
  pdsm::v1::BakeParams p;
  p.set_max_refinement(max_refinement);
  return p;
}

// Bakes into dir/name.exr with `threads` and `batch` samples per task; returns the path.
std::string Bake(const Scene& scene, const TempDir& dir, const std::string& name, int threads = 2,
                 int batch = 0, BakeSummary* summary = nullptr) {
  LocalBakeOptions options;
  options.output_path = dir.File(name + ".exr");
  options.threads = threads;
  options.samples_per_task = batch;
  absl::StatusOr<BakeSummary> s = RunLocalBake(scene, options);
  EXPECT_TRUE(s.ok()) << s.status();
  if (s.ok() && summary != nullptr) *summary = *s;
  return options.output_path;
}

class RefinedBake : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir();
    plain_scene_ = new Scene(LoadBox(*dir_, pdsm::v1::BakeParams()));
    refined_scene_ = new Scene(LoadBox(*dir_, Refined(8)));
    plain_ = Read(Bake(*plain_scene_, *dir_, "plain"));
    refined_ = Read(Bake(*refined_scene_, *dir_, "refined", 2, 0, &summary_));
  }
  static void TearDownTestSuite() {
    delete plain_;
    delete refined_;
    delete plain_scene_;
    delete refined_scene_;
    delete dir_;
  }
  static PdsmImage* Read(const std::string& path) {
    absl::StatusOr<PdsmImage> image = ReadPdsm(path);
    EXPECT_TRUE(image.ok()) << image.status();
    return image.ok() ? new PdsmImage(*std::move(image)) : nullptr;
  }
  // The PDSM pixel's size on the ground near the lit wall.
  static double GroundPixel() {
    return testing::BoxGroundPixel(plain_->header.geometry, glm::dvec3(-0.5, 0, 0));
  }

  static TempDir* dir_;
  static Scene* plain_scene_;
  static Scene* refined_scene_;
  static PdsmImage* plain_;
  static PdsmImage* refined_;
  static BakeSummary summary_;
};
TempDir* RefinedBake::dir_ = nullptr;
Scene* RefinedBake::plain_scene_ = nullptr;
Scene* RefinedBake::refined_scene_ = nullptr;
PdsmImage* RefinedBake::plain_ = nullptr;
PdsmImage* RefinedBake::refined_ = nullptr;
BakeSummary RefinedBake::summary_;

TEST_F(RefinedBake, TheFileSaysHowFarItRefinesAndHoldsRefinedPixels) {
  ASSERT_NE(refined_, nullptr);
  EXPECT_EQ(refined_->header.max_refinement, 8);
  EXPECT_EQ(refined_->header.format_version, 3);
  EXPECT_EQ(plain_->header.format_version, 1);
  int64_t refined_pixels = 0;
  const PdsmGeometry& g = refined_->header.geometry;
  for (int y = 0; y < g.height; ++y) {
    for (int x = 0; x < g.width; ++x) {
      const int f = RefinementOf(refined_->Function(x, y));
      EXPECT_TRUE(f == 1 || f == 8) << x << "," << y;  // one level: the largest factor asked
      refined_pixels += f > 1;
    }
  }
  EXPECT_EQ(refined_pixels, summary_.refinement.pixels);
  EXPECT_EQ(summary_.refinement.factor, 8);
  // Around the box's footprint and its shadow's edges, a small share of the map.
  EXPECT_GT(refined_pixels, 100);
  EXPECT_LT(refined_pixels, g.width * g.height / 10);
}

TEST_F(RefinedBake, UnderTheBoxIsHiddenFromAQuarterPixelOfTheLitWall) {
  ASSERT_NE(refined_, nullptr);
  const double pixel = GroundPixel();
  for (double d : {0.3, 0.5, 0.75, 1.5, 4.0}) {
    for (const glm::dvec3& p : testing::AlongBoxWall(-1, -d * pixel)) {
      EXPECT_GE(QueryAttenuation(*refined_, p), 0.95) << "under the box, " << d << " pixels in";
    }
  }
  // Not vacuous: the unrefined bake reads these half lit (measured 0 a third of a pixel in,
  // 0.49 at one pixel).
  for (const glm::dvec3& p : testing::AlongBoxWall(-1, -0.5 * pixel)) {
    EXPECT_LT(QueryAttenuation(*plain_, p), 0.5);
  }
}

TEST_F(RefinedBake, LitGroundStaysLitUpToTheWallAndTheUmbraReachesTheContact) {
  ASSERT_NE(refined_, nullptr);
  const double pixel = GroundPixel();
  for (double d : {0.002, 0.1, 0.25, 0.5, 1.0, 2.0}) {
    const std::vector<glm::dvec3> points = testing::AlongBoxWall(-1, d * pixel);
    for (const glm::dvec3& p : points) {
      EXPECT_EQ(QueryAttenuation(*refined_, p), 0.0) << "lit ground, " << d << " pixels out";
    }
  }
  for (double d : {0.002, 0.01, 0.05, 0.2}) {
    for (const glm::dvec3& p : testing::AlongBoxWall(+1, d)) {
      EXPECT_GE(QueryAttenuation(*refined_, p), 0.95) << "umbra, " << d << " from the wall";
    }
  }
}

TEST_F(RefinedBake, PenumbraOnTheGroundIsCloserToTheExactAnswer) {
  ASSERT_NE(refined_, nullptr);
  // Ground points beside the box's far side and its front and back walls, where the shadow's
  // edges run.
  std::vector<glm::dvec3> points;
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.5, 2.0);
  while (points.size() < 3000) {
    const glm::dvec3 p(u(rng), 0.0, u(rng) * 0.6);
    if (std::abs(p.x) > 0.5 || std::abs(p.z) > 0.5) points.push_back(p);
  }
  absl::StatusOr<std::vector<double>> exact = ExactAttenuation(*plain_scene_, points);
  ASSERT_TRUE(exact.ok()) << exact.status();
  double plain_error = 0, refined_error = 0, plain_worst = 0, refined_worst = 0;
  int penumbra = 0;
  for (size_t k = 0; k < points.size(); ++k) {
    if (!((*exact)[k] > 0.01 && (*exact)[k] < 0.99)) continue;
    ++penumbra;
    const double a = std::abs(QueryAttenuation(*plain_, points[k]) - (*exact)[k]);
    const double b = std::abs(QueryAttenuation(*refined_, points[k]) - (*exact)[k]);
    plain_error += a, refined_error += b;
    plain_worst = std::max(plain_worst, a), refined_worst = std::max(refined_worst, b);
  }
  ASSERT_GT(penumbra, 200);
  std::printf("penumbra (%d points): mean error %.4f unrefined, %.4f refined; worst %.3f, %.3f\n",
              penumbra, plain_error / penumbra, refined_error / penumbra, plain_worst,
              refined_worst);
  EXPECT_LT(refined_error, plain_error);
  EXPECT_LE(refined_worst, plain_worst);
}

TEST_F(RefinedBake, OffEveryReceiverItReadsAsTheUnrefinedBakeBitForBit) {
  ASSERT_NE(refined_, nullptr);
  // Free space around the box, farther than a few pixels from any surface: no refined
  // sub-pixel is defined there, so every pixel reads its own function, the unrefined one.
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1.8, 1.8), h(0.2, 0.8);
  int compared = 0;
  while (compared < 2000) {
    const glm::dvec3 p(u(rng), h(rng), u(rng));
    if (std::abs(p.x) < 0.7 && std::abs(p.z) < 0.7) continue;
    const double plain = QueryAttenuation(*plain_, p), refined = QueryAttenuation(*refined_, p);
    if (std::isnan(plain)) {  // outside the light's frustum, in both
      ASSERT_TRUE(std::isnan(refined)) << p.x << "," << p.y << "," << p.z;
      continue;
    }
    ASSERT_EQ(refined, plain) << p.x << "," << p.y << "," << p.z;
    ++compared;
  }
}

TEST(RefinedBakeBytes, DoNotDependOnThreadsOrBatches) {
  TempDir dir;
  for (const bool surfaces_only : {false, true}) {
    pdsm::v1::BakeParams overrides = Refined(4);
    overrides.set_surfaces_only(surfaces_only);
    overrides.add_resolution(64);
    overrides.add_resolution(64);
    overrides.set_samples(16);
    const Scene scene = LoadBox(dir, overrides);
    const std::string one = ReadBytes(Bake(scene, dir, "one", 1, 0));
    const std::string two = ReadBytes(Bake(scene, dir, "two", 2, 3));
    ASSERT_FALSE(one.empty());
    EXPECT_EQ(one, two) << (surfaces_only ? "surfaces only" : "full");
    absl::StatusOr<PdsmImage> image = ReadPdsm(dir.File("one.exr"));
    ASSERT_TRUE(image.ok()) << image.status();
    int refined = 0;
    for (int k = 0; k < 64 * 64; ++k) refined += RefinementOf(image->Function(k % 64, k / 64)) > 1;
    EXPECT_GT(refined, 20) << (surfaces_only ? "surfaces only" : "full");
  }
}

// `"refine": false` keeps a receiver's shadows at the base map's resolution. With the ground
// opted out only the box's own surfaces are refined (their bands still reach the ground at the
// contact, where the wall meets it); with both opted out nothing is, and the file reads as the
// unrefined bake bit for bit, while the same scene opted in refines the contact.
TEST(RefinedBakeBytes, ReceiversThatOptOutOfRefinementAreNotRefined) {
  TempDir dir;
  pdsm::v1::BakeParams overrides;
  overrides.add_resolution(64);
  overrides.add_resolution(64);
  overrides.set_samples(16);
  const Scene plain_scene = LoadBox(dir, overrides);
  overrides.set_max_refinement(4);
  const Scene refined_scene = LoadBox(dir, overrides);
  // The box on plane with `"refine": false` on the ground, and also on the box.
  std::string json = kBoxOnPlaneJson;
  const std::string ground = R"("role": "RECEIVER_ONLY"})";
  const std::string box = "3,7,4, 3,4,0]}}";
  ASSERT_NE(json.find(ground), std::string::npos);
  json.replace(json.find(ground), ground.size(), R"("role": "RECEIVER_ONLY", "refine": false})");
  WriteText(dir.File("ground_out.json"), json);
  ASSERT_NE(json.find(box), std::string::npos);
  json.replace(json.find(box), box.size(), R"(3,7,4, 3,4,0]}, "refine": false})");
  WriteText(dir.File("all_out.json"), json);
  absl::StatusOr<Scene> ground_out = LoadSceneFile(dir.File("ground_out.json"), overrides);
  absl::StatusOr<Scene> all_out = LoadSceneFile(dir.File("all_out.json"), overrides);
  ASSERT_TRUE(ground_out.ok()) << ground_out.status();
  ASSERT_TRUE(all_out.ok()) << all_out.status();
  const absl::StatusOr<PdsmImage> plain = ReadPdsm(Bake(plain_scene, dir, "plain"));
  const absl::StatusOr<PdsmImage> refined = ReadPdsm(Bake(refined_scene, dir, "refined"));
  const absl::StatusOr<PdsmImage> box_only = ReadPdsm(Bake(*ground_out, dir, "ground_out"));
  const absl::StatusOr<PdsmImage> none = ReadPdsm(Bake(*all_out, dir, "all_out"));
  ASSERT_TRUE(plain.ok() && refined.ok() && box_only.ok() && none.ok());
  const auto refined_pixels = [](const PdsmImage& image) {
    int n = 0;
    for (int k = 0; k < 64 * 64; ++k) n += RefinementOf(image.Function(k % 64, k / 64)) > 1;
    return n;
  };
  const int all = refined_pixels(*refined), of_the_box = refined_pixels(*box_only);
  std::printf("refined pixels: %d, %d with the ground opted out, %d with both\n", all, of_the_box,
              refined_pixels(*none));
  EXPECT_GT(all, 20);
  EXPECT_LT(of_the_box, all);
  EXPECT_EQ(refined_pixels(*none), 0);
  // Ground points across the lit wall's contact, a pixel either side.
  const double pixel = testing::BoxGroundPixel(plain->header.geometry, glm::dvec3(-0.5, 0, 0));
  int differs = 0;
  for (double d : {-1.0, -0.5, -0.25, -0.1, 0.1, 0.25, 0.5, 1.0}) {
    for (const glm::dvec3& p : testing::AlongBoxWall(-1, d * pixel)) {
      const double base = QueryAttenuation(*plain, p);
      ASSERT_EQ(QueryAttenuation(*none, p), base) << d << " pixels from the wall";
      differs += QueryAttenuation(*refined, p) != base;
    }
  }
  EXPECT_GT(differs, 0) << "the opted-in contact is refined";
}

TEST(RefinedBakeBytes, OnlyAReceiverMaySayWhetherItIsRefined) {
  TempDir dir;
  std::string json = kBoxOnPlaneJson;
  const std::string box = "3,7,4, 3,4,0]}}";
  ASSERT_NE(json.find(box), std::string::npos);
  json.replace(json.find(box), box.size(),
               R"(3,7,4, 3,4,0]}, "role": "CASTER_ONLY", "refine": true})");
  WriteText(dir.File("caster.json"), json);
  const absl::StatusOr<Scene> scene = LoadSceneFile(dir.File("caster.json"), Refined(4));
  ASSERT_FALSE(scene.ok());
  EXPECT_EQ(scene.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(scene.status().message().find("meshes[1].refine"), std::string::npos) << scene.status();
}

TEST(RefinedBakeBytes, AnUnknownRefinementIsRefusedNamingTheField) {
  TempDir dir;
  const std::string path = dir.File("box_on_plane.json");
  WriteText(path, kBoxOnPlaneJson);
  const absl::StatusOr<Scene> scene = LoadSceneFile(path, Refined(3));
  ASSERT_FALSE(scene.ok());
  EXPECT_EQ(scene.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(scene.status().message().find("bake.maxRefinement"), std::string::npos)
      << scene.status();
}

}  // namespace
}  // namespace pdsm
