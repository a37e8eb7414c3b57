// Small scenes and helpers for the extremes suite (ctest -L extremes, docs/accuracy.md): each
// case bakes a tiny scene through the whole local pipeline and compares the file's answers
// with the exact reference (core/reference) or an analytic value.
#ifndef PDSM_TESTS_EXTREMES_EXTREMES_SUPPORT_H_
#define PDSM_TESTS_EXTREMES_EXTREMES_SUPPORT_H_

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <glm/glm.hpp>

#include "core/geometry/light_frame.h"
#include "core/pdsm/pdsm_file.h"
#include "core/pdsm/pdsm_query.h"
#include "core/reference/exact_visibility.h"
#include "core/scene/scene.h"
#include "tests/test_support.h"
#include "worker/local_bake.h"

namespace pdsm::extremes {

// An axis-aligned horizontal quad (two triangles) at height y, world units.
inline TriangleMesh Quad(double x0, double x1, double z0, double z1, double y, MeshRole role) {
  TriangleMesh mesh;
  mesh.label = "quad";
  mesh.role = role;
  mesh.positions_world = {{x0, y, z0}, {x1, y, z0}, {x1, y, z1}, {x0, y, z1}};
  mesh.indices = {0, 1, 2, 0, 2, 3};
  return mesh;
}

// The reference scene of the suite: a 6 x 6 ground (receiver only) at y = 0, a 2 x 2 plate
// (caster and receiver) at y = 2.5, a square light of side `light_size` at y = 5 facing down.
// PDSM 32 x 32, 64 samples, 256-texel shadow maps, lossless (epsilon 0).
inline Scene PlateScene(double light_size = 1.0) {
  Scene scene;
  scene.name = "extremes";
  scene.source_path = "extremes_test";
  scene.meshes = {Quad(-3, 3, -3, 3, 0.0, MeshRole::kReceiverOnly),
                  Quad(-1, 1, -1, 1, 2.5, MeshRole::kCasterAndReceiver)};
  const glm::dvec3 up(0, 0, 1);
  scene.light.shape = LightShape::kRect;
  scene.light.frame = MakeLightFrame({0, 5, 0}, {0, -1, 0}, &up);
  scene.light.half_width = scene.light.half_height = 0.5 * light_size;
  scene.bake.width = scene.bake.height = 32;
  scene.bake.samples = 64;
  scene.bake.shadow_map_resolution = 256;
  scene.bake.epsilon = 0;
  scene.bake.tile_size = 16;
  return scene;
}

// Moves every mesh and every light by `offset` (world units). A sun's centre is the plan's
// (placed before the scene), so moving it changes nothing.
inline void Translate(Scene* scene, const glm::dvec3& offset) {
  for (TriangleMesh& mesh : scene->meshes) {
    for (glm::dvec3& p : mesh.positions_world) p += offset;
  }
  scene->light.frame.center += offset;
  for (SceneLight& light : scene->more_lights) light.spec.frame.center += offset;
}

struct Baked {
  BakeSummary summary;
  PdsmImage image;
};

// Bakes into a temporary file and reads it back. Fails the test (nullopt) on error.
inline std::optional<Baked> Bake(const Scene& scene, int threads = 2) {
  pdsm::testing::TempDir dir;
  LocalBakeOptions options;
  options.output_path = dir.File("out.exr");
  options.threads = threads;
  absl::StatusOr<BakeSummary> summary = RunLocalBake(scene, options);
  EXPECT_TRUE(summary.ok()) << summary.status();
  if (!summary.ok()) return std::nullopt;
  absl::StatusOr<PdsmImage> image = ReadPdsm(options.output_path);
  EXPECT_TRUE(image.ok()) << image.status();
  if (!image.ok()) return std::nullopt;
  return Baked{*summary, *std::move(image)};
}

// An n x n grid of points on the plane y = height, x and z in [-half, half].
inline std::vector<glm::dvec3> Grid(double half, int n, double height) {
  std::vector<glm::dvec3> points;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      points.emplace_back(-half + 2 * half * (i + 0.5) / n, height,
                          -half + 2 * half * (j + 0.5) / n);
    }
  }
  return points;
}

struct Errors {
  double mean = 0, max = 0;
  size_t count = 0;  // points compared (both values defined)
  size_t nan = 0;    // points where the PDSM answered NaN
};

// The PDSM's answers against the exact attenuation at `points`.
inline Errors CompareWithExact(const PdsmImage& pdsm, const Scene& scene,
                               const std::vector<glm::dvec3>& points) {
  Errors e;
  absl::StatusOr<std::vector<double>> exact = ExactAttenuation(scene, points);
  EXPECT_TRUE(exact.ok()) << exact.status();
  if (!exact.ok()) return e;
  for (size_t k = 0; k < points.size(); ++k) {
    const double baked = QueryAttenuation(pdsm, points[k]);
    if (std::isnan(baked)) {
      ++e.nan;
      continue;
    }
    const double err = std::abs(baked - (*exact)[k]);
    e.mean += err;
    e.max = std::max(e.max, err);
    ++e.count;
  }
  if (e.count > 0) e.mean /= static_cast<double>(e.count);
  return e;
}

inline size_t VertexCount(const PdsmImage& image) { return image.vertices.size(); }

}  // namespace pdsm::extremes

#endif  // PDSM_TESTS_EXTREMES_EXTREMES_SUPPORT_H_
