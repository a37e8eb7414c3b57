#include "core/pipeline/refinement_pass.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <memory>
#include <vector>

#include "core/bake/level_groups.h"
#include "core/bake/plan_fingerprint.h"
#include "core/bake/scan_windows.h"
#include "core/geometry/light_frame.h"
#include "core/pdsm/refined_pixel.h"
#include "core/scene/scene.h"

namespace pdsm {
namespace {

constexpr int kSize = 64;

// A receiving ground at depth 10 under a rect light, and a small plate caster at depth 7: the
// tests supply the base map's functions themselves.
Scene MakeScene(int max_refinement) {
  Scene scene;
  scene.name = "refinement_pass_test";
  TriangleMesh ground;
  ground.role = MeshRole::kReceiverOnly;
  ground.positions_world = {{-10, 0, -10}, {10, 0, -10}, {10, 0, 10}, {-10, 0, 10}};
  ground.indices = {0, 2, 1, 0, 3, 2};
  TriangleMesh plate;
  plate.role = MeshRole::kCasterOnly;
  plate.positions_world = {{-1, 3, -1}, {1, 3, -1}, {0, 3, 1}};
  plate.indices = {0, 1, 2};
  scene.meshes = {ground, plate};
  const glm::dvec3 up(0, 0, 1);
  scene.light.shape = LightShape::kRect;
  scene.light.frame = MakeLightFrame({0, 10, 0}, {0, -1, 0}, &up);
  scene.light.half_width = scene.light.half_height = 0.5;
  scene.bake.width = scene.bake.height = kSize;
  scene.bake.tile_size = 16;
  scene.bake.samples = 4;
  scene.bake.shadow_map_resolution = kSize;
  scene.bake.max_refinement = max_refinement;
  return scene;
}

class RefinementPassTest : public testing::Test {
 protected:
  void SetUp() override {
    absl::StatusOr<std::shared_ptr<const SceneIndex>> index = SceneIndex::Build(scene_);
    ASSERT_TRUE(index.ok()) << index.status();
    index_ = *index;
    absl::StatusOr<BakePlan> base = PlanBake(*index_);
    ASSERT_TRUE(base.ok()) << base.status();
    base_ = *std::move(base);
    ASSERT_GT(base_.receivers.TriangleCount(), 0u) << "a refined plan keeps its receivers";
  }

  // The base map's tiles: pixels left of column `edge` hidden from depth 9 (in front of the
  // ground), the others lit.
  BaseTileSource EdgeTiles(int edge) const {
    return [this, edge](int t) -> absl::StatusOr<PdsmTile> {
      const TileRect rect = base_.tile(t);
      PdsmTile tile;
      tile.x0 = rect.x0, tile.y0 = rect.y0, tile.width = rect.width, tile.height = rect.height;
      tile.offsets.push_back(0);
      for (int j = 0; j < rect.height; ++j) {
        for (int i = 0; i < rect.width; ++i) {
          if (rect.x0 + i < edge) {
            tile.vertices.push_back({9.0f, 0.0f});
            tile.vertices.push_back({9.0f, 1.0f});
          }
          tile.offsets.push_back(tile.vertices.size());
        }
      }
      return tile;
    };
  }

  Scene scene_ = MakeScene(4);
  std::shared_ptr<const SceneIndex> index_;
  BakePlan base_;
};

TEST_F(RefinementPassTest, AShadowEdgeOnTheGroundRefinesTheTwoColumnsBesideIt) {
  absl::StatusOr<std::shared_ptr<const RefinedPixels>> refined =
      SelectRefinedPixels(base_, EdgeTiles(20), 2);
  ASSERT_TRUE(refined.ok()) << refined.status();
  EXPECT_EQ((*refined)->factor(), 4);  // a difference of 1: the largest factor
  EXPECT_EQ((*refined)->count(), 2 * kSize);
  for (int t = 0; t < base_.tile_count(); ++t) {
    for (const RefinedPixel& p : (*refined)->Tile(t)) {
      EXPECT_TRUE(p.x == 19 || p.x == 20) << p.x << "," << p.y;
      ASSERT_EQ(p.bands.size(), 1u);
      EXPECT_LT(p.bands[0].lo, 10.0);  // the ground's depth, a little around it
      EXPECT_GT(p.bands[0].hi, 10.0);
      EXPECT_LT(p.bands[0].hi - p.bands[0].lo, 0.1);
    }
  }
  // The same on one thread: the result does not depend on the scheduling.
  absl::StatusOr<std::shared_ptr<const RefinedPixels>> again =
      SelectRefinedPixels(base_, EdgeTiles(20), 1);
  ASSERT_TRUE(again.ok());
  for (int t = 0; t < base_.tile_count(); ++t) {
    ASSERT_TRUE(std::ranges::equal((*refined)->Tile(t), (*again)->Tile(t))) << t;
  }
  // Without refinement, nothing.
  Scene off = MakeScene(1);
  absl::StatusOr<BakePlan> plain = PlanBake(off);
  ASSERT_TRUE(plain.ok());
  plain->receivers = base_.receivers;
  absl::StatusOr<std::shared_ptr<const RefinedPixels>> none =
      SelectRefinedPixels(*plain, EdgeTiles(20), 2);
  ASSERT_TRUE(none.ok());
  EXPECT_TRUE((*none)->empty());
}

TEST_F(RefinementPassTest, TheLevelScansOnlyTheRefinedPixelsSubPixelsAroundTheGround) {
  absl::StatusOr<std::shared_ptr<const RefinedPixels>> refined =
      SelectRefinedPixels(base_, EdgeTiles(20), 2);
  ASSERT_TRUE(refined.ok());
  absl::StatusOr<BakePlan> level = PlanRefinementLevel(*index_, std::nullopt, base_, *refined);
  ASSERT_TRUE(level.ok()) << level.status();
  EXPECT_EQ(level->geometry().width, 4 * kSize);
  EXPECT_EQ(level->header.shadow_map_resolution, 4 * kSize);
  EXPECT_EQ(level->geometry().s_min, base_.geometry().s_min);  // the same frustum
  EXPECT_EQ(level->geometry().z_far, base_.geometry().z_far);
  EXPECT_EQ(level->samples, base_.samples);
  int rays = 0;
  for (int t = 0; t < level->tile_count(); ++t) {
    const TileRect rect = level->tile(t);
    const bool holds = rect.x0 <= 4 * 20 + 3 && rect.x0 + rect.width > 4 * 19;
    EXPECT_TRUE(!level->tile_has_casters[t] || holds) << "a task for a tile without rays: " << t;
    const std::optional<TileWindows> windows = ScanWindows(*level, rect);
    ASSERT_TRUE(windows.has_value());
    for (int j = 0; j < rect.height; ++j) {
      for (int i = 0; i < rect.width; ++i) {
        const int x = rect.x0 + i;
        const std::span<const DepthWindow> w = windows->Pixel(j * rect.width + i);
        if (x / 4 != 19 && x / 4 != 20) {
          EXPECT_TRUE(w.empty()) << x;
          continue;
        }
        ++rays;
        ASSERT_EQ(w.size(), 1u) << x;
        EXPECT_LE(w[0].lo, 10.0);
        EXPECT_GE(w[0].hi, 10.0);
      }
    }
  }
  EXPECT_EQ(rays, 8 * 4 * kSize);
  // A refined pixel's level is its own plan: the fingerprint covers the rays it bakes.
  absl::StatusOr<std::shared_ptr<const RefinedPixels>> other =
      SelectRefinedPixels(base_, EdgeTiles(40), 2);
  ASSERT_TRUE(other.ok());
  absl::StatusOr<BakePlan> other_level = PlanRefinementLevel(*index_, std::nullopt, base_, *other);
  ASSERT_TRUE(other_level.ok());
  EXPECT_NE(PlanFingerprint(*level), PlanFingerprint(*other_level));
  EXPECT_NE(PlanFingerprint(*level), PlanFingerprint(base_));
}

TEST_F(RefinementPassTest, TheSpliceKeepsTheOwnFunctionAndPlacesEachSubPixel) {
  absl::StatusOr<std::shared_ptr<const RefinedPixels>> refined =
      SelectRefinedPixels(base_, EdgeTiles(20), 2);
  ASSERT_TRUE(refined.ok());
  absl::StatusOr<BakePlan> level = PlanRefinementLevel(*index_, std::nullopt, base_, *refined);
  ASSERT_TRUE(level.ok());
  // The level's tiles: level pixel (x, y) of a refined pixel holds a window at the ground with
  // A = x / 1000 in it; one level tile was never stored (no caster reached it).
  const int missing = level->TileIndexAt(80, 0);
  const LevelTileSource level_tile = [&](int t) -> absl::StatusOr<std::optional<PdsmTile>> {
    if (t == missing) return std::optional<PdsmTile>();
    const TileRect rect = level->tile(t);
    const TileWindows windows = *ScanWindows(*level, rect);
    PdsmTile tile;
    tile.x0 = rect.x0, tile.y0 = rect.y0, tile.width = rect.width, tile.height = rect.height;
    tile.offsets.push_back(0);
    for (int j = 0; j < rect.height; ++j) {
      for (int i = 0; i < rect.width; ++i) {
        const std::span<const DepthWindow> w = windows.Pixel(j * rect.width + i);
        if (!w.empty()) {
          const float a = static_cast<float>(rect.x0 + i) / 1000;
          const float nan = std::nanf("");
          for (const Vertex v : {Vertex{kUndefinedFrom, nan}, Vertex{float(w[0].lo), a},
                                 Vertex{float(w[0].hi), a}, Vertex{float(w[0].hi), nan}}) {
            tile.vertices.push_back(v);
          }
        }
        tile.offsets.push_back(tile.vertices.size());
      }
    }
    return std::optional<PdsmTile>(std::move(tile));
  };
  const BaseTileSource base_tiles = EdgeTiles(20);
  std::atomic<int> spliced{0};
  ASSERT_TRUE(SpliceRefinedTiles(
                  base_, *level, base_tiles, level_tile,
                  [&](const PdsmTile& tile) {
                    ++spliced;
                    absl::StatusOr<PdsmTile> before =
                        base_tiles(base_.TileIndexAt(tile.x0, tile.y0));
                    for (int j = 0; j < tile.height; ++j) {
                      for (int i = 0; i < tile.width; ++i) {
                        const std::span<const Vertex> s = tile.Function(i, j);
                        const std::span<const Vertex> own = OwnFunction(s);
                        const std::span<const Vertex> was = before->Function(i, j);
                        EXPECT_TRUE(std::ranges::equal(own, was));
                        const int x = tile.x0 + i;
                        EXPECT_EQ(RefinementOf(s), x == 19 || x == 20 ? 4 : 1) << x;
                        if (RefinementOf(s) == 1) continue;
                        EXPECT_EQ(PixelFunctionFault(s, 4), "");
                        for (int a = 0; a < 4; ++a) {
                          const double got = SubPixelAttenuation(s, 4, a, 0, 10.0);
                          // Level pixel 80 + a of rows 0-15 lies in the missing tile: lit in
                          // its windows.
                          const bool lost = x == 20 && tile.y0 + j < 4;
                          EXPECT_EQ(got, lost ? 0.0 : static_cast<float>(4 * x + a) / 1000)
                              << x << " " << a;
                        }
                        EXPECT_TRUE(std::isnan(SubPixelAttenuation(s, 4, 0, 0, 5.0)));
                      }
                    }
                    return absl::OkStatus();
                  },
                  2)
                  .ok());
  EXPECT_EQ(spliced, kSize / 16);  // the tiles holding columns 19 and 20
}

TEST_F(RefinementPassTest, ARingOfRaysTakesSmallGroupsAndOneRegionOneGroup) {
  // Refined pixels in a square ring against refined pixels filling a square.
  const auto make = [&](bool ring) {
    std::vector<std::vector<RefinedPixel>> by_tile(base_.tile_count());
    // Under the plate's shadow, where casters reach.
    for (int y = 24; y < 40; ++y) {
      for (int x = 24; x < 40; ++x) {
        const bool edge = x == 24 || x == 39 || y == 24 || y == 39;
        if (ring && !edge) continue;
        by_tile[base_.TileIndexAt(x / 16 * 16, y / 16 * 16)].push_back({x, y, {{9.9, 10.1}}});
      }
    }
    return std::make_shared<const RefinedPixels>(base_.geometry(), 16, 8, std::move(by_tile));
  };
  absl::StatusOr<BakePlan> ring = PlanRefinementLevel(*index_, std::nullopt, base_, make(true));
  absl::StatusOr<BakePlan> fill = PlanRefinementLevel(*index_, std::nullopt, base_, make(false));
  ASSERT_TRUE(ring.ok() && fill.ok());
  EXPECT_LT(ring->group_side, fill->group_side);
  EXPECT_EQ(LevelGroupSide(*ring), ring->group_side);
}

}  // namespace
}  // namespace pdsm
