#include "core/pdsm/pdsm_tile_cache.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "core/pdsm/pdsm_query.h"
#include "core/pdsm/pdsm_test_images.h"
#include "tests/test_support.h"

namespace pdsm {
namespace {

using ::pdsm::testing::CutTile;
using ::pdsm::testing::CutTiles;
using ::pdsm::testing::FullHeader;
using ::pdsm::testing::RandomImage;
using ::pdsm::testing::WriteTiles;

// World points all over the window (and some outside it), at depths across the functions'.
std::vector<glm::dvec3> PointsOver(const PdsmHeader& header, int n, uint32_t seed) {
  const PdsmGeometry& g = header.geometry;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-0.05, 1.05), depth(0.2, 30.0);
  std::vector<glm::dvec3> points;
  for (int k = 0; k < n; ++k) {
    const double s = g.s_min + u(rng) * (g.s_max - g.s_min);
    const double t = g.t_min + u(rng) * (g.t_max - g.t_min);
    points.push_back(g.frame.WorldFromLight({s, t, depth(rng)}));  // orthographic: (s, t) = (x, y)
  }
  return points;
}

class PdsmTileCacheTest : public ::testing::Test {
 protected:
  void SetUp() override {
    // 130 x 70 in tiles of 16: partial tiles on the right and bottom edges.
    image_ = RandomImage(FullHeader(130, 70, 16), 21, /*big_count=*/500);
    path_ = (dir_.path() / "map.exr").string();
    ASSERT_TRUE(WriteTiles(path_, image_.header, CutTiles(image_)).ok());
  }
  PdsmTileCache Open(int64_t budget) {
    absl::StatusOr<PdsmReader> reader = PdsmReader::Open(path_);
    EXPECT_TRUE(reader.ok()) << reader.status();
    return PdsmTileCache(*std::move(reader), budget);
  }

  ::pdsm::testing::TempDir dir_;
  PdsmImage image_;
  std::string path_;
};

TEST_F(PdsmTileCacheTest, EachTileReadAloneIsTheTileOfTheWholeMap) {
  absl::StatusOr<PdsmReader> reader = PdsmReader::Open(path_);
  ASSERT_TRUE(reader.ok()) << reader.status();
  for (int ty = 0; ty < 5; ++ty) {
    for (int tx = 0; tx < 9; ++tx) {
      absl::StatusOr<PdsmTile> tile = reader->ReadTile(0, tx, ty);
      ASSERT_TRUE(tile.ok()) << tile.status();
      const PdsmTile expected = CutTile(image_, tx * 16, ty * 16);
      EXPECT_EQ(tile->x0, expected.x0);
      EXPECT_EQ(tile->width, expected.width) << tx << ", " << ty;
      EXPECT_EQ(tile->height, expected.height) << tx << ", " << ty;
      EXPECT_EQ(tile->offsets, expected.offsets) << tx << ", " << ty;
      EXPECT_EQ(tile->vertices, expected.vertices) << tx << ", " << ty;
    }
  }
  EXPECT_EQ(reader->ReadTile(0, 9, 0).status().code(), absl::StatusCode::kOutOfRange);
  EXPECT_EQ(reader->ReadTile(0, 0, -1).status().code(), absl::StatusCode::kOutOfRange);
  EXPECT_EQ(reader->ReadTile(1, 0, 0).status().code(), absl::StatusCode::kOutOfRange);
}

TEST_F(PdsmTileCacheTest, AnswersAreTheWholeMapsBitForBitWhateverTheBudget) {
  const std::vector<glm::dvec3> points = PointsOver(image_.header, 4000, 5);
  int inside = 0;
  // A budget of one byte keeps one tile: every other lookup reads again.
  for (const int64_t budget : {int64_t{1}, int64_t{20000}, int64_t{1} << 30}) {
    PdsmTileCache cache = Open(budget);
    for (const glm::dvec3& p : points) {
      const double expected = QueryAttenuation(image_, p);
      absl::StatusOr<double> got = cache.Attenuation(0, p);
      ASSERT_TRUE(got.ok()) << got.status();
      if (std::isnan(expected)) {
        EXPECT_TRUE(std::isnan(*got));
        EXPECT_EQ(cache.TileKey(0, p), -1);
        continue;
      }
      ++inside;
      ASSERT_EQ(*got, expected) << "budget " << budget;
    }
    if (budget == 1) EXPECT_GT(cache.tiles_read(), 1000) << "evicting";
    if (budget == (int64_t{1} << 30)) EXPECT_EQ(cache.tiles_read(), 45) << "each tile once";
  }
  EXPECT_GT(inside, 3 * 3000);
}

TEST_F(PdsmTileCacheTest, HoldsNoMoreThanItsBudget) {
  const int64_t budget = 40000;  // a few of these tiles
  PdsmTileCache cache = Open(budget);
  int64_t most = 0;
  for (const glm::dvec3& p : PointsOver(image_.header, 3000, 9)) {
    ASSERT_TRUE(cache.Attenuation(0, p).ok());
    most = std::max(most, cache.bytes_held());
  }
  EXPECT_LE(most, budget);
  EXPECT_GT(most, budget / 4);
}

TEST_F(PdsmTileCacheTest, ThreadsShareOneCache) {
  const std::vector<glm::dvec3> points = PointsOver(image_.header, 2000, 13);
  PdsmTileCache cache = Open(30000);
  std::vector<std::thread> threads;
  std::vector<int> wrong(4, 0);
  for (int t = 0; t < 4; ++t) {
    threads.emplace_back([&, t] {
      for (size_t k = t; k < points.size(); k += 2) {
        const double expected = QueryAttenuation(image_, points[k]);
        absl::StatusOr<double> got = cache.Attenuation(0, points[k]);
        if (!got.ok() || !(*got == expected || (std::isnan(*got) && std::isnan(expected)))) {
          ++wrong[t];
        }
      }
    });
  }
  for (std::thread& t : threads) t.join();
  EXPECT_EQ(wrong, std::vector<int>(4, 0));
}

}  // namespace
}  // namespace pdsm
