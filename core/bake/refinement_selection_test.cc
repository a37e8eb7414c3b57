#include "core/bake/refinement_selection.h"

#include <limits>
#include <span>
#include <vector>

#include <gtest/gtest.h>

namespace pdsm {
namespace {

using Function = std::vector<Vertex>;

// An orthographic map of `size` x `size` pixels 0.5 wide, with geometry down to depth 10.
PdsmGeometry Ortho(int size) {
  PdsmGeometry g;
  g.projection = Projection::kOrthographic;
  g.width = g.height = size;
  g.s_min = g.t_min = 0;
  g.s_max = g.t_max = 0.5 * size;
  g.z_near = 0;
  g.z_far = 10;
  return g;
}

// Hidden from depth z on.
Function StepAt(float z) { return {{z, 0.0f}, {z, 1.0f}}; }

// Every point of `rect` with the one window `w`.
TileWindows Uniform(const TileRect& rect, DepthWindow w) {
  TileWindows out;
  out.rect = rect;
  out.offsets.push_back(0);
  for (int k = 0; k < rect.width * rect.height; ++k) {
    out.windows.push_back(w);
    out.offsets.push_back(out.windows.size());
  }
  return out;
}

// A receiver plane at depth `z` under every pixel: each pixel's window a little around it, and
// the rays between pixels meeting it at z.
PairReceivers PlaneAt(const PdsmGeometry& g, const TileRect& rect, double z) {
  const TileRect grown = GrownByOnePixel(g, rect);
  return PairReceivers{Uniform(grown, {z - 0.01, z + 0.01}), Uniform(grown, {z, z}),
                       Uniform(grown, {z, z})};
}

// A map whose pixels x < edge are hidden from depth 1 and the rest lit.
struct EdgeMap {
  int edge;
  Function hidden = StepAt(1), lit = {};
  std::span<const Vertex> operator()(int x, int /*y*/) const { return x < edge ? hidden : lit; }
};

TEST(RefinementForGap, TheSmallestFactorThatBringsTheStepUnderTheThreshold) {
  EXPECT_EQ(RefinementForGap(1.0, 8), 8);
  EXPECT_EQ(RefinementForGap(0.3, 8), 4);
  EXPECT_EQ(RefinementForGap(0.2, 8), 2);
  EXPECT_EQ(RefinementForGap(0.15, 8), 2);
  EXPECT_EQ(RefinementForGap(kRefinementGapThreshold, 8), 1);
  EXPECT_EQ(RefinementForGap(1.0, 2), 2);
  EXPECT_EQ(RefinementForGap(1.0, 1), 1);
  EXPECT_EQ(RefinementForGap(std::numeric_limits<double>::quiet_NaN(), 8), 1);
}

TEST(SelectRefinement, RefinesBothSidesOfAShadowEdgeOnAReceiverOverItsWindow) {
  const PdsmGeometry g = Ortho(8);
  const TileRect all{0, 0, 0, 8, 8};
  const std::vector<PixelRefinement> out =
      SelectRefinement(g, all, 4, PlaneAt(g, all, 5.0), EdgeMap{3});
  for (int y = 0; y < 8; ++y) {
    for (int x = 0; x < 8; ++x) {
      const PixelRefinement& r = out[y * 8 + x];
      if (x == 2 || x == 3) {
        EXPECT_EQ(r.factor, 4) << x << "," << y;
        ASSERT_EQ(r.bands.size(), 1u);
        EXPECT_EQ(r.bands[0], (DepthWindow{4.99, 5.01}));
      } else {
        EXPECT_EQ(r.factor, 1) << x << "," << y;
        EXPECT_TRUE(r.bands.empty());
      }
    }
  }
  // Off: nothing.
  for (const PixelRefinement& r : SelectRefinement(g, all, 1, PlaneAt(g, all, 5.0), EdgeMap{3})) {
    EXPECT_EQ(r.factor, 1);
  }
}

TEST(SelectRefinement, ATileSeesItsNeighboursAcrossItsBorder) {
  // The edge lies between column 3 (the left tile) and 4 (the right tile's first column).
  const PdsmGeometry g = Ortho(8);
  const TileRect left_rect{0, 0, 0, 4, 8}, right_rect{1, 4, 0, 4, 8};
  const std::vector<PixelRefinement> left =
      SelectRefinement(g, left_rect, 2, PlaneAt(g, left_rect, 5.0), EdgeMap{4});
  const std::vector<PixelRefinement> right =
      SelectRefinement(g, right_rect, 2, PlaneAt(g, right_rect, 5.0), EdgeMap{4});
  for (int y = 0; y < 8; ++y) {
    EXPECT_EQ(left[y * 4 + 3].factor, 2);
    EXPECT_EQ(right[y * 4 + 0].factor, 2);
    for (int x = 0; x < 3; ++x) EXPECT_EQ(left[y * 4 + x].factor, 1);
    for (int x = 1; x < 4; ++x) EXPECT_EQ(right[y * 4 + x].factor, 1);
  }
}

TEST(SelectRefinement, ADifferenceWhereNoReceiverIsIsNotRefined) {
  // The rays differ between depths 1 and 2 (one hidden from 1, the other from 2), but the only
  // receiver lies at depth 5, where both are hidden: nothing to refine.
  const PdsmGeometry g = Ortho(8);
  const TileRect all{0, 0, 0, 8, 8};
  const Function one = StepAt(1), two = StepAt(2);
  const auto map = [&](int x, int) -> std::span<const Vertex> { return x % 2 ? one : two; };
  for (const PixelRefinement& r : SelectRefinement(g, all, 8, PlaneAt(g, all, 5.0), map)) {
    EXPECT_EQ(r.factor, 1);
  }
  // With the receiver between them, every pixel is refined, by the largest factor.
  for (const PixelRefinement& r : SelectRefinement(g, all, 8, PlaneAt(g, all, 1.5), map)) {
    EXPECT_EQ(r.factor, 8);
  }
}

TEST(SelectRefinement, TheFactorFollowsTheDifference) {
  // 0.3 hidden against lit: 0.3 / 4 <= 0.1 < 0.3 / 2.
  const PdsmGeometry g = Ortho(4);
  const TileRect all{0, 0, 0, 4, 4};
  const Function half = {{1.0f, 0.0f}, {1.0f, 0.3f}}, lit = {};
  const auto map = [&](int x, int) -> std::span<const Vertex> { return x < 2 ? half : lit; };
  const std::vector<PixelRefinement> out = SelectRefinement(g, all, 8, PlaneAt(g, all, 5.0), map);
  EXPECT_EQ(out[1].factor, 4);
  EXPECT_EQ(out[2].factor, 4);
  EXPECT_EQ(out[0].factor, 1);
}

TEST(MergeBands, SortsAndJoinsOverlaps) {
  std::vector<DepthWindow> bands = {{5, 6}, {1, 2}, {1.5, 3}, {6, 7}, {9, 9.5}};
  MergeBands(&bands);
  EXPECT_EQ(bands, (std::vector<DepthWindow>{{1, 3}, {5, 7}, {9, 9.5}}));
}

}  // namespace
}  // namespace pdsm
