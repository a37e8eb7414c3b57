// Scan conversion cases of thesis 3.1 on hand-made shadow maps: depth inside the bounds
// (fig. 3.4a), behind them (3.4b), exit into a lit texel (3.4c), and the one-texel ray.
#include "worker/scan_convert.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include <gtest/gtest.h>

namespace pdsm {
namespace {

constexpr float kEmpty = std::numeric_limits<float>::infinity();

// A 1-row shadow map of `depths` on a lattice of unit texels starting at s = 0.
struct Row {
  std::vector<float> depths;
  ShadowMapView View() const {
    ShadowMapView view;
    view.depth = depths.data();
    view.lattice = ShadowMapLattice{0.0, 0.0, 1.0, 1.0};
    view.window = ShadowMapWindow{0, 0, static_cast<int>(depths.size()), 1};
    return view;
  }
};

// Orthographic ray crossing the row from s = 0.5 + ... : depth z maps linearly to s, so texel
// k spans depths [z0 + k * dz, z0 + (k + 1) * dz] (the first and last clipped to the ray).
RayInShadowMap OrthoRay(double s_near, double s_far, double z_near, double z_far) {
  return RayInShadowMap{{s_near, 0.5}, {s_far, 0.5}, z_near, z_far};
}

std::vector<Event> Convert(const Row& row, const RayInShadowMap& ray, Projection p) {
  std::vector<Event> events;
  ScanConvertRay(row.View(), ray, p, &events);
  return events;
}

TEST(ScanConvert, OccluderInsidePieceEntersAtItsDepth) {
  // Texel 1 spans depths [2, 3] along the ray; its occluder is at 2.5.
  const Row row{{kEmpty, 2.5f, kEmpty}};
  const auto events = Convert(row, OrthoRay(0.0, 3.0, 1.0, 4.0), Projection::kOrthographic);
  ASSERT_EQ(events.size(), 2u);
  EXPECT_EQ(events[0], (Event{2.5f, +1}));
  EXPECT_EQ(events[1], (Event{3.0f, -1}));  // texel 2 is lit: leave at its boundary
}

TEST(ScanConvert, OccluderInFrontOfPieceEntersAtTheBound) {
  // Texel 1 spans [2, 3]; occluder at 1.2 is nearer than the piece: shadowed from z_in = 2.
  const Row row{{kEmpty, 1.2f, 1.0f, kEmpty}};
  const auto events = Convert(row, OrthoRay(0.0, 4.0, 1.0, 5.0), Projection::kOrthographic);
  ASSERT_EQ(events.size(), 2u);
  EXPECT_EQ(events[0], (Event{2.0f, +1}));
  EXPECT_EQ(events[1], (Event{4.0f, -1}));  // stays shadowed through texel 2, leaves at 4
}

TEST(ScanConvert, ShadowedRayLitAgainThenBehindAnotherOccluder) {
  // Texel 0 shadowed from 1.5; texel 1 occluder at 2.7 inside [2, 3]: lit from 2 to 2.7.
  const Row row{{1.5f, 2.7f}};
  const auto events = Convert(row, OrthoRay(0.0, 2.0, 1.0, 3.0), Projection::kOrthographic);
  ASSERT_EQ(events.size(), 3u);
  EXPECT_EQ(events[0], (Event{1.5f, +1}));
  EXPECT_EQ(events[1], (Event{2.0f, -1}));
  EXPECT_EQ(events[2], (Event{2.7f, +1}));
}

TEST(ScanConvert, OccluderBehindTheRayPieceLeavesItLit) {
  const Row row{{9.0f, 9.0f, 9.0f}};
  EXPECT_TRUE(Convert(row, OrthoRay(0.0, 3.0, 1.0, 4.0), Projection::kOrthographic).empty());
}

TEST(ScanConvert, OneTexelRayIsShadowedFromTheOccluderToInfinity) {
  // The light-centre sample: the perspective ray does not move in the shadow map.
  const Row row{{kEmpty, 3.25f, kEmpty}};
  const RayInShadowMap ray{{1.5, 0.5}, {1.5, 0.5}, 1.0, std::numeric_limits<double>::infinity()};
  const auto events = Convert(row, ray, Projection::kPerspective);
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0], (Event{3.25f, +1}));
}

TEST(ScanConvert, PerspectiveDepthsAreLinearInInverseDepth) {
  // w = 1/z runs from 1 (z = 1) at s = 0 to 0 (z = inf) at s = 4: the boundary between
  // texels k-1 and k is at w = 1 - k/4, i.e. z = 4 / (4 - k).
  const Row row{{kEmpty, 0.5f, kEmpty, kEmpty}};
  const RayInShadowMap ray{{0.0, 0.5}, {4.0, 0.5}, 1.0, std::numeric_limits<double>::infinity()};
  const auto events = Convert(row, ray, Projection::kPerspective);
  ASSERT_EQ(events.size(), 2u);
  EXPECT_FLOAT_EQ(events[0].z, 4.0f / 3.0f);  // enters at texel 1's near bound
  EXPECT_EQ(events[0].count, +1);
  EXPECT_FLOAT_EQ(events[1].z, 2.0f);  // texel 2 lit: leaves at z = 4 / 2
  EXPECT_EQ(events[1].count, -1);
}

TEST(ScanConvert, DiagonalRayVisitsEveryCrossedTexel) {
  // A 3x3 map whose diagonal texels hold occluders nearer than the ray: the ray from
  // (0.1, 0.1) to (2.9, 2.9) crosses (0,0) (0,1) or (1,0) (1,1) ... (2,2); shadowed all along
  // the diagonal texels, lit in the off-diagonal ones it clips.
  std::vector<float> depths(9, kEmpty);
  for (int k = 0; k < 3; ++k) depths[k * 3 + k] = 0.0f;
  ShadowMapView view{depths.data(), ShadowMapLattice{0, 0, 1, 1}, ShadowMapWindow{0, 0, 3, 3}};
  std::vector<Event> events;
  ScanConvertRay(view, RayInShadowMap{{0.1, 0.1}, {2.9, 2.85}, 1.0, 2.0}, Projection::kOrthographic,
                 &events);
  ASSERT_FALSE(events.empty());
  EXPECT_EQ(events.front(), (Event{1.0f, +1}));
  int sum = 0;
  for (const Event& e : events) sum += e.count;
  EXPECT_EQ(sum, 1);  // ends in the shadowed texel (2, 2)
  for (size_t k = 1; k < events.size(); ++k) EXPECT_LT(events[k - 1].z, events[k].z);
}

}  // namespace
}  // namespace pdsm

namespace pdsm {
namespace {

// A segment that is one piece of a ray (surfaces-only windows) closes a shadow at its end, so
// pieces of one ray add up: two pieces give the same attenuation inside them as the whole ray.
TEST(ScanConvert, ClosedSegmentsAddUpToTheWholeRay) {
  const std::vector<float> depths = {kEmpty, 1.5f, 1.5f, kEmpty, 3.2f, kEmpty};
  ShadowMapView view;
  view.depth = depths.data();
  view.lattice = ShadowMapLattice{0.0, 0.0, 1.0, 1.0};
  view.window = ShadowMapWindow{0, 0, 6, 1};
  // Depth z lies at s = z - 1 along this orthographic ray.
  auto ray = [](double z0, double z1) {
    return RayInShadowMap{{z0 - 1.0, 0.5}, {z1 - 1.0, 0.5}, z0, z1};
  };
  std::vector<Event> whole, pieces;
  ScanConvertRay(view, ray(1.0, 7.0), Projection::kOrthographic, &whole);
  // Pieces [2.5, 3.5] (inside the first shadow, which ends at 4) and [4.5, 6.5].
  EXPECT_EQ(
      ScanConvertRay(view, ray(2.5, 3.5), Projection::kOrthographic, &pieces, SegmentEnd::kClose),
      2);
  ScanConvertRay(view, ray(4.5, 6.5), Projection::kOrthographic, &pieces, SegmentEnd::kClose);
  auto hidden_at = [](const std::vector<Event>& events, double z) {
    int sum = 0;
    for (const Event& e : events) sum += e.z <= z ? e.count : 0;
    return sum;
  };
  for (double z : {2.5, 3.0, 3.49, 4.5, 5.0, 5.5, 6.0, 6.49}) {
    EXPECT_EQ(hidden_at(pieces, z), hidden_at(whole, z)) << "z " << z;
  }
  // Each piece ends lit: the counts sum to zero.
  EXPECT_EQ(hidden_at(pieces, 100.0), 0);
  EXPECT_EQ(hidden_at(whole, 3.0), 1);
  EXPECT_EQ(hidden_at(whole, 5.0), 1);  // behind the occluder at 3.2
}

// The occupancy table (BuildOccupancySums) against counting the box texel by texel.
TEST(ScanConvert, OccupancySumsCountTheCastersOfEveryBox) {
  constexpr int kW = 13, kH = 7;
  std::mt19937 rng(3);
  std::vector<float> depth(kW * kH);
  for (float& d : depth) d = rng() % 3 == 0 ? 1.0f : kEmpty;
  std::vector<uint32_t> sums;
  BuildOccupancySums(depth.data(), kW, kH, &sums);
  ASSERT_EQ(sums.size(), size_t{(kW + 1) * (kH + 1)});
  for (int y0 = 0; y0 < kH; ++y0) {
    for (int y1 = y0; y1 < kH; ++y1) {
      for (int x0 = 0; x0 < kW; ++x0) {
        for (int x1 = x0; x1 < kW; ++x1) {
          uint32_t count = 0;
          for (int y = y0; y <= y1; ++y) {
            for (int x = x0; x <= x1; ++x) count += depth[y * kW + x] != kEmpty;
          }
          const uint32_t table = sums[(y1 + 1) * (kW + 1) + x1 + 1] - sums[y0 * (kW + 1) + x1 + 1] -
                                 sums[(y1 + 1) * (kW + 1) + x0] + sums[y0 * (kW + 1) + x0];
          ASSERT_EQ(table, count) << x0 << "," << y0 << " " << x1 << "," << y1;
        }
      }
    }
  }
}

// Skipping rays by the occupancy table changes no event: random rays (ends on texel corners
// and edges too, open and closed, both projections) through a sparse map give the same events
// with the table as without, and the table does skip some of them.
TEST(ScanConvert, TheOccupancySkipGivesTheSameEvents) {
  constexpr int kW = 64, kH = 48;
  std::mt19937 rng(11);
  std::vector<float> depth(kW * kH, kEmpty);
  for (int blob = 0; blob < 6; ++blob) {  // a few small casters
    const int cx = static_cast<int>(rng() % kW), cy = static_cast<int>(rng() % kH);
    for (int y = std::max(0, cy - 2); y < std::min(kH, cy + 3); ++y) {
      for (int x = std::max(0, cx - 3); x < std::min(kW, cx + 4); ++x) {
        depth[y * kW + x] = 1.0f + static_cast<float>(rng() % 1000) / 250.0f;
      }
    }
  }
  std::vector<uint32_t> sums;
  BuildOccupancySums(depth.data(), kW, kH, &sums);
  ShadowMapView plain;
  plain.depth = depth.data();
  plain.lattice = ShadowMapLattice{0.0, 0.0, 1.0, 1.0};
  plain.window = ShadowMapWindow{0, 0, kW, kH};
  ShadowMapView skipping = plain;
  skipping.occupancy = sums.data();
  std::uniform_real_distribution<double> sx(0.0, kW), sy(0.0, kH), len(0.0, 12.0), z(0.5, 3.0);
  int skipped = 0, walked = 0;
  for (int i = 0; i < 20000; ++i) {
    glm::dvec2 a(sx(rng), sy(rng));
    if (i % 4 == 0) a = glm::floor(a);  // on a texel corner
    const double angle = 6.283185307179586 * (rng() % 360) / 360.0;
    glm::dvec2 b = a + len(rng) * glm::dvec2(std::cos(angle), std::sin(angle));
    if (i % 5 == 0) b.x = std::floor(b.x);  // on a texel edge
    b = glm::clamp(b, glm::dvec2(0.0), glm::dvec2(kW, kH) - 1e-9);
    const double z_near = z(rng);
    const RayInShadowMap ray{a, b, z_near, z_near + len(rng) + 0.1};
    const Projection projection = i % 2 ? Projection::kPerspective : Projection::kOrthographic;
    const SegmentEnd end = i % 3 ? SegmentEnd::kOpen : SegmentEnd::kClose;
    std::vector<Event> expected, got;
    ScanConvertRay(plain, ray, projection, &expected, end);
    const int64_t n = ScanConvertRay(skipping, ray, projection, &got, end);
    ASSERT_EQ(got, expected) << "ray " << i;
    (n == 0 ? skipped : walked) += 1;
  }
  EXPECT_GT(skipped, 1000);
  EXPECT_GT(walked, 1000);
}

}  // namespace
}  // namespace pdsm
