// The ray-traced reference against the exact one: agreement within the stated Monte-Carlo
// bound on examples/plates, convergence with N, receivers that never shadow themselves, and
// precision far from the origin (rebasing on the light centre).
#include "core/reference/embree_visibility.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "core/reference/accuracy_points.h"
#include "core/reference/exact_visibility.h"
#include "core/scene/scene_loader.h"

namespace pdsm {
namespace {

Scene LoadExample(const std::string& name) {
  absl::StatusOr<Scene> scene =
      LoadSceneFile(std::string(PDSM_SOURCE_DIR) + "/examples/" + name + "/scene.json");
  EXPECT_TRUE(scene.ok()) << scene.status();
  return scene.ok() ? *std::move(scene) : Scene{};
}

std::vector<glm::dvec3> PlatesPoints(const Scene& scene) {
  absl::StatusOr<AccuracyPoints> points =
      MakeAccuracyPoints(scene, AccuracyPointCounts{300, 300}, 5);
  EXPECT_TRUE(points.ok()) << points.status();
  std::vector<glm::dvec3> all = points->surface;
  all.insert(all.end(), points->free_space.begin(), points->free_space.end());
  return all;
}

TEST(EmbreeReference, AgreesWithExactWithinTheStatedBound) {
  const Scene scene = LoadExample("plates");
  const std::vector<glm::dvec3> points = PlatesPoints(scene);
  absl::StatusOr<std::vector<double>> exact = ExactAttenuation(scene, points);
  ASSERT_TRUE(exact.ok()) << exact.status();
  constexpr int kSamples = 1024;
  absl::StatusOr<std::vector<double>> embree = EmbreeAttenuation(scene, points, kSamples);
  ASSERT_TRUE(embree.ok()) << embree.status();
  const ErrorStats e = CompareAttenuation(*embree, *exact);
  ASSERT_EQ(e.count, points.size());
  // Each point's error has standard deviation <= the bound, so no single point may be 5
  // bounds off, and the mean |error| stays under the bound (sqrt(2/pi) of it for Gaussians).
  const double bound = EmbreeErrorBound(kSamples);
  std::printf("embree %d vs exact: mean %.5f p95 %.5f max %.5f (bound %.4f)\n", kSamples, e.mean,
              e.p95, e.max, bound);
  EXPECT_LT(e.max, 5 * bound);
  EXPECT_LT(e.mean, bound);
}

TEST(EmbreeReference, ConvergesWithSamples) {
  const Scene scene = LoadExample("plates");
  const std::vector<glm::dvec3> points = PlatesPoints(scene);
  absl::StatusOr<std::vector<double>> exact = ExactAttenuation(scene, points);
  ASSERT_TRUE(exact.ok()) << exact.status();
  double previous = 1.0;
  for (int n : {16, 256, 4096}) {
    absl::StatusOr<std::vector<double>> embree = EmbreeAttenuation(scene, points, n);
    ASSERT_TRUE(embree.ok()) << embree.status();
    const ErrorStats e = CompareAttenuation(*embree, *exact);
    std::printf("N=%d: mean %.6f p95 %.6f max %.6f\n", n, e.mean, e.p95, e.max);
    // 16x the samples: at least 4x less error (1/sqrt(N)); stratification does better.
    EXPECT_LT(e.mean, previous / 4) << n;
    previous = e.mean;
  }
}

TEST(EmbreeReference, ReceiversDoNotShadowThemselves) {
  const Scene scene = LoadExample("plates");
  // The ground far from every caster's shadow, and the top of the triangle plate at y = 2
  // (outside the upper plate's shadow: the exact method's answer is the truth there).
  std::vector<glm::dvec3> points;
  for (int k = 0; k < 100; ++k) points.emplace_back(9.0 - 0.05 * k, 0.0, -9.0 + 0.013 * k);
  for (int k = 0; k < 100; ++k) {
    const double u = (k % 10 + 0.5) / 10.0, v = (k / 10 + 0.5) / 10.0;
    points.emplace_back(0.5 + 2.0 * u * (1 - v) + v * 1.0, 2.0, 0.5 + 1.8 * v);
  }
  absl::StatusOr<std::vector<double>> exact = ExactAttenuation(scene, points);
  absl::StatusOr<std::vector<double>> embree = EmbreeAttenuation(scene, points, 256);
  ASSERT_TRUE(exact.ok() && embree.ok());
  for (size_t k = 0; k < 100; ++k) EXPECT_EQ((*embree)[k], 0.0) << k;
  const ErrorStats e = CompareAttenuation(*embree, *exact);
  EXPECT_LT(e.max, 5 * EmbreeErrorBound(256));
}

TEST(EmbreeReference, FarFromTheOriginKeepsItsPrecision) {
  Scene scene = LoadExample("plates");
  const glm::dvec3 far(3e5, -2e5, 7e5);
  for (TriangleMesh& mesh : scene.meshes) {
    for (glm::dvec3& p : mesh.positions_world) p += far;
  }
  scene.light.frame.center += far;
  const Scene near = LoadExample("plates");
  std::vector<glm::dvec3> points = PlatesPoints(near);
  absl::StatusOr<std::vector<double>> expected = EmbreeAttenuation(near, points, 256);
  for (glm::dvec3& p : points) p += far;
  absl::StatusOr<std::vector<double>> moved = EmbreeAttenuation(scene, points, 256);
  ASSERT_TRUE(expected.ok() && moved.ok());
  // Rebased in double, the floats Embree sees are nearly the same: same samples, same
  // answers, except for rays that graze an edge within float rounding.
  const ErrorStats e = CompareAttenuation(*moved, *expected);
  EXPECT_LT(e.mean, 1e-3);
}

TEST(EmbreeReference, BehindTheLightIsNanAndBadSampleCountsAreRefused) {
  const Scene scene = LoadExample("plates");
  const std::vector<glm::dvec3> points = {{0, 11, 0}, {0, 0, 0}};
  absl::StatusOr<std::vector<double>> a = EmbreeAttenuation(scene, points, 64);
  ASSERT_TRUE(a.ok());
  EXPECT_TRUE(std::isnan((*a)[0]));
  EXPECT_FALSE(std::isnan((*a)[1]));
  EXPECT_EQ(EmbreeAttenuation(scene, points, 0).status().code(),
            absl::StatusCode::kInvalidArgument);
}

TEST(EmbreeReference, SunLightShadowsFollowTheSunDirection) {
  const Scene scene = LoadExample("sun_pillars");
  // Pillar 1 stands on x,z in [-2.3,-1.7] x [-2.3,-1.7], 5 high; the sun travels along
  // (-0.4,-1,-0.3), so the shadow falls towards -x, -z: a ground point 1 unit (0.4, 0.3)
  // along that way from the base is in umbra; (-1,0,-3) and (6,0,6) see the sun past both.
  const std::vector<glm::dvec3> points = {{-2.4, 0, -2.3}, {-1.0, 0, -3.0}, {6, 0, 6}};
  absl::StatusOr<std::vector<double>> a = EmbreeAttenuation(scene, points, 1024);
  ASSERT_TRUE(a.ok()) << a.status();
  EXPECT_GT((*a)[0], 0.99);
  EXPECT_EQ((*a)[1], 0.0);
  EXPECT_EQ((*a)[2], 0.0);
}

// Weighted (light_weighting.h): each Embree sample carries its weight; the estimate agrees with
// the exact weighted reference as the unweighted one does, and the weighting changes the answer
// well beyond that agreement (on plates' 3x3 light 10 above, by up to a few hundredths).
TEST(EmbreeReference, WeightedAgreesWithTheExactWeightedReference) {
  const Scene scene = LoadExample("plates");
  const std::vector<glm::dvec3> points = PlatesPoints(scene);
  constexpr int kSamples = 1024;
  const double bound = EmbreeErrorBound(kSamples);
  absl::StatusOr<std::vector<double>> unweighted = ExactAttenuation(scene, points);
  ASSERT_TRUE(unweighted.ok()) << unweighted.status();
  // Every plates point is below the horizontal light, so an upward receiver sees all of it.
  for (const WeightingSpec& spec : {WeightingSpec{LightWeighting::kEmitter, {}},
                                    WeightingSpec{LightWeighting::kIrradiance, {0, 1, 0}}}) {
    absl::StatusOr<std::vector<double>> exact = ExactAttenuation(scene, points, spec);
    ASSERT_TRUE(exact.ok()) << exact.status();
    absl::StatusOr<std::vector<double>> embree =
        EmbreeAttenuation(scene, points, kSamples, /*seed=*/1, spec);
    ASSERT_TRUE(embree.ok()) << embree.status();
    const ErrorStats e = CompareAttenuation(*embree, *exact);
    ASSERT_EQ(e.count, points.size()) << LightWeightingName(spec.kind);
    // The weighted estimate is nearer the weighted reference than the unweighted one is.
    const ErrorStats away = CompareAttenuation(*embree, *unweighted);
    std::printf("embree %s vs exact: mean %.5f max %.5f; vs unweighted exact: mean %.5f max %.4f\n",
                LightWeightingName(spec.kind), e.mean, e.max, away.mean, away.max);
    EXPECT_LT(e.max, 5 * bound) << LightWeightingName(spec.kind);
    EXPECT_LT(e.mean, bound) << LightWeightingName(spec.kind);
    EXPECT_GT(away.mean, 5 * e.mean) << LightWeightingName(spec.kind);
  }
}

}  // namespace
}  // namespace pdsm
