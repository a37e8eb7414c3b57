#include "core/bake/receiver_windows.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numbers>
#include <random>

#include "core/bake/bake_plan.h"
#include "core/geometry/light_frame.h"
#include "core/scene/scene.h"

namespace pdsm {
namespace {

// A tilted ground, a steep ramp and a small box of receivers under a rect light or the sun.
Scene MakeScene(LightShape shape) {
  Scene scene;
  scene.name = "receiver_windows_test";
  TriangleMesh ground;
  ground.role = MeshRole::kReceiverOnly;
  ground.positions_world = {{-10, -1, -10}, {10, 1, -10}, {10, 1, 10}, {-10, -1, 10}};
  ground.indices = {0, 1, 2, 0, 2, 3};
  TriangleMesh ramp;  // nearly parallel to the light's rays
  ramp.positions_world = {{-2, 0, 1}, {-1.8, 6, 1}, {-1.8, 6, 3}, {-2, 0, 3}};
  ramp.indices = {0, 1, 2, 0, 2, 3};
  TriangleMesh plate;
  plate.positions_world = {{1, 3, -2}, {3, 3.5, -2}, {2, 3.2, 0}};
  plate.indices = {0, 1, 2};
  scene.meshes = {ground, ramp, plate};
  const glm::dvec3 up(0, 0, 1);
  scene.light.shape = shape;
  scene.light.frame = shape == LightShape::kSun
                          ? MakeLightFrame({0, 0, 0}, glm::normalize(glm::dvec3(0.3, -1, 0.2)), &up)
                          : MakeLightFrame({0, 10, 0}, {0, -1, 0}, &up);
  scene.light.half_width = scene.light.half_height = 1.5;
  scene.light.tan_half_angle = std::tan(0.5 * std::numbers::pi / 180.0);
  scene.bake.width = 48;
  scene.bake.height = 40;
  scene.bake.tile_size = 16;
  scene.bake.samples = 4;
  scene.bake.surfaces_only = true;
  return scene;
}

class ReceiverWindowsTest : public testing::TestWithParam<LightShape> {};

// The property queries rely on: for a random point on any receiver, each of the (up to four)
// pixels a bilinear query at it reads has a window holding the point's depth.
TEST_P(ReceiverWindowsTest, EveryReceiverPointIsInsideItsFourPixelsWindows) {
  const Scene scene = MakeScene(GetParam());
  absl::StatusOr<BakePlan> plan = PlanBake(scene);
  ASSERT_TRUE(plan.ok()) << plan.status();
  const PdsmGeometry& g = plan->geometry();
  std::map<int, TileWindows> windows;
  for (const TileRect& tile : AllTiles(*plan))
    windows.emplace(tile.index, ComputeReceiverWindows(*plan, tile));

  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int checked = 0;
  for (const TriangleMesh& mesh : scene.meshes) {
    for (size_t k = 0; k + 2 < mesh.indices.size(); k += 3) {
      for (int trial = 0; trial < 400; ++trial) {
        double u = unit(rng), v = unit(rng);
        if (u + v > 1) u = 1 - u, v = 1 - v;
        const glm::dvec3 p =
            mesh.positions_world[mesh.indices[k]] +
            u * (mesh.positions_world[mesh.indices[k + 1]] -
                 mesh.positions_world[mesh.indices[k]]) +
            v * (mesh.positions_world[mesh.indices[k + 2]] - mesh.positions_world[mesh.indices[k]]);
        const std::optional<PdsmPoint> at = g.Locate(p);
        if (!at) continue;
        // The pixels BilinearAttenuation reads (clamped at the border).
        const int fx = static_cast<int>(std::floor(at->px - 0.5));
        const int fy = static_cast<int>(std::floor(at->py - 0.5));
        for (int dy = 0; dy < 2; ++dy) {
          for (int dx = 0; dx < 2; ++dx) {
            const int x = std::clamp(fx + dx, 0, g.width - 1);
            const int y = std::clamp(fy + dy, 0, g.height - 1);
            const int tile_index = (y / 16) * plan->tiles_x + x / 16;
            const TileWindows& tw = windows.at(tile_index);
            const size_t pixel =
                static_cast<size_t>(y - tw.rect.y0) * tw.rect.width + (x - tw.rect.x0);
            bool inside = false;
            for (const DepthWindow& w : tw.Pixel(pixel)) inside |= w.lo <= at->z && at->z <= w.hi;
            std::string listed;
            for (const DepthWindow& w : tw.Pixel(pixel)) {
              listed += " [" + std::to_string(w.lo) + ", " + std::to_string(w.hi) + "]";
            }
            ASSERT_TRUE(inside) << "point " << p.x << "," << p.y << "," << p.z << " depth " << at->z
                                << " at pixel coords " << at->px << "," << at->py
                                << " not in a window of pixel " << x << "," << y << ":" << listed;
            ++checked;
          }
        }
      }
    }
  }
  EXPECT_GT(checked, 7000);  // 5 triangles x 400 points x 4 pixels, less any outside
}

// Windows are sorted, disjoint and thin where the receiver faces the light: the whole point of
// the mode is that they cover far less than the depth range.
TEST_P(ReceiverWindowsTest, WindowsAreSortedDisjointAndThin) {
  const Scene scene = MakeScene(GetParam());
  absl::StatusOr<BakePlan> plan = PlanBake(scene);
  ASSERT_TRUE(plan.ok());
  const PdsmGeometry& g = plan->geometry();
  double covered = 0;
  size_t pixels_with_windows = 0;
  for (const TileRect& tile : AllTiles(*plan)) {
    const TileWindows tw = ComputeReceiverWindows(*plan, tile);
    ASSERT_EQ(tw.offsets.size(), static_cast<size_t>(tile.width) * tile.height + 1);
    for (size_t p = 0; p + 1 < tw.offsets.size(); ++p) {
      const auto list = tw.Pixel(p);
      pixels_with_windows += !list.empty();
      for (size_t k = 0; k < list.size(); ++k) {
        ASSERT_LE(list[k].lo, list[k].hi);
        if (k > 0) ASSERT_LT(list[k - 1].hi, list[k].lo);
        covered += list[k].hi - list[k].lo;
      }
    }
  }
  ASSERT_GT(pixels_with_windows, 0u);
  const double mean_fraction = covered / pixels_with_windows / (g.z_far - g.z_near);
  std::printf("mean window cover: %.3f of the depth range\n", mean_fraction);
  EXPECT_LT(mean_fraction, 0.25);
}

std::string ShapeName(const testing::TestParamInfo<LightShape>& info) {
  return info.param == LightShape::kSun ? "Sun" : "Rect";
}

INSTANTIATE_TEST_SUITE_P(Lights, ReceiverWindowsTest,
                         testing::Values(LightShape::kRect, LightShape::kSun), ShapeName);

}  // namespace
}  // namespace pdsm
