#include "worker/shadow_map_renderer.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <functional>
#include <limits>
#include <random>
#include <regex>
#include <string>
#include <thread>
#include <vector>

#include "worker/shadow_map_shaders.h"  // generated: the embedded GLSL sources

namespace pdsm {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

struct Mesh {
  std::vector<glm::vec3> positions;
  std::vector<uint32_t> indices;

  void AddTriangle(glm::vec3 a, glm::vec3 b, glm::vec3 c) {
    const auto base = static_cast<uint32_t>(positions.size());
    positions.insert(positions.end(), {a, b, c});
    indices.insert(indices.end(), {base, base + 1, base + 2});
  }
  // Corners in order around the quad.
  void AddQuad(glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec3 d) {
    AddTriangle(a, b, c);
    AddTriangle(a, c, d);
  }
  // Axis-aligned rectangle [x0, x1] x [y0, y1] at depth z, parallel to the light.
  void AddParallelQuad(float x0, float x1, float y0, float y1, float z) {
    AddQuad({x0, y0, z}, {x1, y0, z}, {x1, y1, z}, {x0, y1, z});
  }
};

// Lattice of pitch 1/16 whose edges sit at 0.16 and 0.32 texel from round s and t values, so
// no texel centre comes near the (round) edges of the test quads: coverage is unambiguous, and
// a half-texel error in the projection moves a boundary by one texel.
ShadowMapCamera TestCamera() {
  ShadowMapCamera camera;
  camera.lattice = {.s_origin = -2.01, .t_origin = -2.02, .pitch_s = 0.0625, .pitch_t = 0.0625};
  camera.window = {.x0 = 8, .y0 = 8, .width = 80, .height = 72};  // s in [-1.51, 3.49)
  camera.z_clip_near = 0.5;
  camera.z_clip_far = 50;
  return camera;
}

double CentreS(const ShadowMapCamera& c, int px) {
  return c.lattice.EdgeS(c.window.x0 + px) + 0.5 * c.lattice.pitch_s;
}
double CentreT(const ShadowMapCamera& c, int py) {
  return c.lattice.EdgeT(c.window.y0 + py) + 0.5 * c.lattice.pitch_t;
}

// Expected depth at a texel centre (s, t), +inf for no caster, NaN for "not checked".
using ExpectedDepth = std::function<double(double s, double t)>;

// Compares every texel with `expected` (relative tolerance); reports at most a few failures.
void ExpectDepths(const ShadowMapCamera& camera, const std::vector<float>& depth,
                  const ExpectedDepth& expected, double relative_tolerance = 1e-6) {
  ASSERT_EQ(depth.size(), static_cast<size_t>(camera.window.width) * camera.window.height);
  int failures = 0;
  for (int py = 0; py < camera.window.height; ++py) {
    for (int px = 0; px < camera.window.width; ++px) {
      const double want = expected(CentreS(camera, px), CentreT(camera, py));
      if (std::isnan(want)) continue;
      const float got = depth[static_cast<size_t>(py) * camera.window.width + px];
      const bool ok = std::isinf(want) ? (std::isinf(got) && got > 0)
                                       : std::abs(got - want) <= relative_tolerance * want;
      if (!ok && ++failures <= 5) {
        ADD_FAILURE() << "texel (" << px << ", " << py << ") s=" << CentreS(camera, px)
                      << " t=" << CentreT(camera, py) << ": got " << got << ", want " << want;
      }
    }
  }
  EXPECT_EQ(failures, 0);
}

bool Inside(double v, double lo, double hi) { return v > lo && v < hi; }

int CountFinite(const std::vector<float>& depth) {
  int n = 0;
  for (float d : depth) n += std::isfinite(d) ? 1 : 0;
  return n;
}

bool BitIdentical(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

class ShadowMapRendererTest : public ::testing::Test {
 protected:
  void SetUp() override {
    absl::StatusOr<std::unique_ptr<ShadowMapRenderer>> renderer = ShadowMapRenderer::Create();
    ASSERT_TRUE(renderer.ok()) << renderer.status();
    renderer_ = *std::move(renderer);
  }
  void Upload(const Mesh& mesh) {
    ASSERT_TRUE(renderer_->SetGeometry(mesh.positions, mesh.indices).ok());
  }
  std::vector<float> RenderOrDie(const ShadowMapCamera& camera) {
    std::vector<float> depth;
    const absl::Status status = renderer_->Render(camera, &depth);
    EXPECT_TRUE(status.ok()) << status;
    return depth;
  }

  std::unique_ptr<ShadowMapRenderer> renderer_;
};

// (1) x in [0, 10] at z = 5 projects to s in [0, 2]; texels whose centres are inside read 5.
// The far edges, s = t = 2.1, sit at 0.76 and 0.92 texel while the near ones sit at 0.16 and
// 0.32, so a half-texel shift either way moves one boundary.
TEST_F(ShadowMapRendererTest, ParallelQuadCoversTexelsWhoseCentresAreInside) {
  Mesh mesh;
  mesh.AddParallelQuad(0, 10.5, 0, 10.5, 5);
  Upload(mesh);
  const ShadowMapCamera camera = TestCamera();
  const std::vector<float> depth = RenderOrDie(camera);
  ExpectDepths(camera, depth, [](double s, double t) {
    return Inside(s, 0, 2.1) && Inside(t, 0, 2.1) ? 5.0 : INFINITY;
  });
  EXPECT_EQ(CountFinite(depth), 34 * 34);  // lattice texels 32..65 in s and in t
}

TEST_F(ShadowMapRendererTest, ConstantDepthBiasIsAdded) {
  Mesh mesh;
  mesh.AddParallelQuad(0, 10, 0, 10, 5);
  Upload(mesh);
  ShadowMapCamera camera = TestCamera();
  camera.depth_bias = 0.25;
  camera.slope_bias = 1;  // a parallel plane has no slope
  ExpectDepths(
      camera, RenderOrDie(camera),
      [](double s, double t) { return Inside(s, 0, 2) && Inside(t, 0, 2) ? 5.25 : INFINITY; },
      1e-5);
}

// (2) The sample at (a, b) = (1, 0) moves the projection by -a / z = -0.2 in s.
TEST_F(ShadowMapRendererTest, SampleOffsetShiftsCoverage) {
  Mesh mesh;
  mesh.AddParallelQuad(0, 10, 0, 10, 5);
  Upload(mesh);
  ShadowMapCamera camera = TestCamera();
  camera.sample = {1.0, 0.0};
  ExpectDepths(camera, RenderOrDie(camera), [](double s, double t) {
    return Inside(s, -0.2, 1.8) && Inside(t, 0, 2) ? 5.0 : INFINITY;
  });
  camera.sample = {0.0, -0.5};  // and by -b / z = +0.1 in t
  ExpectDepths(camera, RenderOrDie(camera), [](double s, double t) {
    return Inside(s, 0, 2) && Inside(t, 0.1, 2.1) ? 5.0 : INFINITY;
  });
}

// (3) The nearest caster wins whatever the drawing order.
TEST_F(ShadowMapRendererTest, NearestCasterWins) {
  Mesh far_first;
  far_first.AddParallelQuad(0, 12, 0, 12, 6);        // s, t in [0, 2]
  far_first.AddParallelQuad(1.5, 4.5, 1.5, 4.5, 3);  // s, t in [0.5, 1.5]
  Mesh near_first;
  near_first.AddParallelQuad(1.5, 4.5, 1.5, 4.5, 3);
  near_first.AddParallelQuad(0, 12, 0, 12, 6);
  const ExpectedDepth expected = [](double s, double t) {
    if (Inside(s, 0.5, 1.5) && Inside(t, 0.5, 1.5)) return 3.0;
    if (Inside(s, 0, 2) && Inside(t, 0, 2)) return 6.0;
    return double{INFINITY};
  };
  const ShadowMapCamera camera = TestCamera();
  for (const Mesh* mesh : {&far_first, &near_first}) {
    Upload(*mesh);
    ExpectDepths(camera, RenderOrDie(camera), expected);
  }
}

// (4) A triangle through the near plane and past the light, and one wholly behind the light.
// The first lies in the plane z = 1.5 + x, which the ray (s, t, 1) meets at z = 1.5 / (1 - s):
// in front of the near plane (z = 1) for s in (-0.5, 1), in front of the light but nearer than
// z_clip_near for s < -0.5. GL must keep exactly the part past z_clip_near.
TEST_F(ShadowMapRendererTest, GeometryCrossingNearPlaneIsClipped) {
  const glm::dvec3 p0(-4, -3, -2.5), p1(6, -3, 7.5), p2(1, 5, 2.5);
  Mesh mesh;
  mesh.AddTriangle(p0, p1, p2);
  mesh.AddTriangle({-1, -1, -3}, {1, -1, -3}, {0, 1, -1});  // behind the light
  Upload(mesh);
  ShadowMapCamera camera = TestCamera();
  camera.z_clip_near = 1.0;
  const glm::dvec3 normal = glm::cross(p1 - p0, p2 - p0);
  int clipped = 0;
  ExpectDepths(
      camera, RenderOrDie(camera),
      [&](double s, double t) {
        const glm::dvec3 ray(s, t, 1);
        const double z = glm::dot(normal, p0) / glm::dot(normal, ray);
        if (!(z > 0)) return double{INFINITY};  // meets the plane behind the light, if at all
        // Barycentric coordinates of the hit point; texels within 1e-3 of an edge are skipped.
        const glm::dvec3 hit = z * ray;
        const double area = glm::dot(normal, normal);
        const double b1 = glm::dot(glm::cross(hit - p0, p2 - p0), normal) / area;
        const double b2 = glm::dot(glm::cross(p1 - p0, hit - p0), normal) / area;
        const double margin = std::min({b1, b2, 1 - b1 - b2});
        if (std::abs(margin) < 1e-3 || std::abs(z - camera.z_clip_near) < 1e-3) return double{NAN};
        if (margin < 0) return double{INFINITY};
        if (z < camera.z_clip_near) {
          ++clipped;
          return double{INFINITY};
        }
        return z;
      },
      1e-5);
  EXPECT_GT(clipped, 100);  // the clipped part is in view
}

// Depth testing uses the *biased* depth. Plane B (z = 2.45 + x / 2, so 2.45 / (1 - s / 2)
// along a ray) passes from in front of quad A (z = 5) to behind it at s = 1.02; with a large
// slope bias there is a band where B is nearer but its biased depth is not, and A must win.
TEST_F(ShadowMapRendererTest, NearestBiasedDepthWins) {
  Mesh mesh;
  mesh.AddParallelQuad(0, 10, 0, 10, 5);  // A: s, t in [0, 2]
  mesh.AddQuad({-2, -10, 1.45}, {8, -10, 6.45}, {8, 10, 6.45}, {-2, 10, 1.45});  // B
  Upload(mesh);
  ShadowMapCamera camera = TestCamera();
  camera.slope_bias = 4;
  const auto z_b = [](double s) { return 2.45 / (1 - 0.5 * s); };
  const auto bias_b = [&](double s) {  // slope_bias * depth change per texel
    return camera.slope_bias * 1.225 / ((1 - 0.5 * s) * (1 - 0.5 * s)) * camera.lattice.pitch_s;
  };
  int a_wins = 0, b_wins = 0;
  ExpectDepths(
      camera, RenderOrDie(camera),
      [&](double s, double t) {
        if (!Inside(s, 0.1, 1.2) || !Inside(t, 0.1, 1.9)) return double{NAN};  // inside A and B
        if (z_b(s) < 5 - 1e-3 && z_b(s) + 0.9 * bias_b(s) > 5 + 1e-3) {
          ++a_wins;
          return 5.0;
        }
        if (z_b(s) + 1.1 * bias_b(s) < 5 - 1e-3) {
          ++b_wins;
          return z_b(s) + bias_b(s);
        }
        return double{NAN};
      },
      0.05);
  EXPECT_GT(a_wins, 50);
  EXPECT_GT(b_wins, 200);
}

// (5) Sun: sample direction (0.5, 0, 1) shears z = 2 by -0.5 * 2 = -1 in s; geometry past
// z_clip_far is clipped.
TEST_F(ShadowMapRendererTest, OrthographicShearShiftsCoverage) {
  Mesh mesh;
  mesh.AddParallelQuad(0, 2, 0, 2, 2);
  mesh.AddParallelQuad(29, 33, -1, 3, 60);  // s in [-1, 3] but beyond z_clip_far = 50
  Upload(mesh);
  ShadowMapCamera camera = TestCamera();
  camera.projection = Projection::kOrthographic;
  camera.sample = {0.5, 0.0};
  ExpectDepths(camera, RenderOrDie(camera), [](double s, double t) {
    return Inside(s, -1, 1) && Inside(t, 0, 2) ? 2.0 : INFINITY;
  });
  camera.z_clip_far = 70;  // now the far quad is in range and shows around the near one
  ExpectDepths(camera, RenderOrDie(camera), [](double s, double t) {
    if (Inside(s, -1, 1) && Inside(t, 0, 2)) return 2.0;
    return Inside(s, -1, 3) && Inside(t, -1, 3) ? 60.0 : double{INFINITY};
  });
}

// (6) Plane z = 4 + x / 2 (so z = 4 / (1 - s / 2) along the ray (s, t, 1)). With slope_bias 1
// the stored depth exceeds the true depth by about one texel's depth change.
TEST_F(ShadowMapRendererTest, SlopeBiasAddsOneTexelOfDepthChange) {
  Mesh mesh;
  mesh.AddQuad({-6, -6, 1}, {2, -6, 5}, {2, 6, 5}, {-6, 6, 1});
  Upload(mesh);
  ShadowMapCamera camera = TestCamera();
  const auto true_depth = [](double s) { return 4.0 / (1.0 - 0.5 * s); };
  const auto depth_change_per_texel = [&](double s) {
    return 2.0 / ((1.0 - 0.5 * s) * (1.0 - 0.5 * s)) * camera.lattice.pitch_s;
  };
  // The quad covers s in [-6, 0.4] and |t| < 6 / z; `inside` keeps 0.1 away from its edges.
  const auto inside = [&](double s, double t) {
    return Inside(s, -5.9, 0.3) && std::abs(t) < 6.0 / true_depth(s) - 0.1;
  };
  const auto outside = [&](double s, double t) {
    return !Inside(s, -6.1, 0.5) || std::abs(t) > 6.0 / true_depth(s) + 0.1;
  };
  for (double footprint_scale : {1.0, 2.5}) {
    camera.slope_bias = 1;
    camera.footprint_scale = footprint_scale;
    const std::vector<float> depth = RenderOrDie(camera);
    int checked = 0;
    for (int py = 0; py < camera.window.height; ++py) {
      for (int px = 0; px < camera.window.width; ++px) {
        const double s = CentreS(camera, px), t = CentreT(camera, py);
        if (!inside(s, t)) continue;
        ++checked;
        const double bias = depth[py * camera.window.width + px] - true_depth(s);
        const double want = footprint_scale * depth_change_per_texel(s);
        ASSERT_GE(bias, 0.9 * want) << "s=" << s << " t=" << t;
        ASSERT_LE(bias, 1.1 * want) << "s=" << s << " t=" << t;
      }
    }
    EXPECT_GT(checked, 500);
  }
  camera.slope_bias = 0;  // without bias the tilted plane's depth is exact
  ExpectDepths(
      camera, RenderOrDie(camera),
      [&](double s, double t) {
        if (inside(s, t)) return true_depth(s);
        return outside(s, t) ? double{INFINITY} : double{NAN};
      },
      1e-5);
}

// A scene with edges everywhere: tilted and parallel quads and seeded random triangles.
Mesh BusyScene() {
  Mesh mesh;
  mesh.AddParallelQuad(0, 10, 0, 10, 5);
  mesh.AddQuad({-6, -6, 1}, {2, -6, 5}, {2, 6, 5}, {-6, 6, 1});
  std::mt19937 rng(1234);
  std::uniform_real_distribution<float> xy(-8, 12), z(1, 9);
  for (int i = 0; i < 200; ++i) {
    const float cz = z(rng);
    mesh.AddTriangle({xy(rng), xy(rng), cz}, {xy(rng), xy(rng), z(rng)}, {xy(rng), xy(rng), cz});
  }
  return mesh;
}

// (7) A window split into pieces equals the same window rendered whole.
TEST_F(ShadowMapRendererTest, PiecesMatchWholeWindow) {
  ShadowMapRenderer::Options options;
  options.max_piece_size = 17;  // rounded down to 16: pieces of 16, 16, ... and a remainder
  absl::StatusOr<std::unique_ptr<ShadowMapRenderer>> pieces = ShadowMapRenderer::Create(options);
  ASSERT_TRUE(pieces.ok()) << pieces.status();
  const Mesh mesh = BusyScene();
  Upload(mesh);
  ASSERT_TRUE((*pieces)->SetGeometry(mesh.positions, mesh.indices).ok());
  for (Projection projection : {Projection::kPerspective, Projection::kOrthographic}) {
    ShadowMapCamera camera = TestCamera();
    camera.projection = projection;
    camera.sample =
        projection == Projection::kPerspective ? glm::dvec2(0.7, -0.3) : glm::dvec2(0.1, -0.05);
    camera.depth_bias = 0.01;
    camera.slope_bias = 1.5;
    const std::vector<float> whole = RenderOrDie(camera);
    std::vector<float> split;
    ASSERT_TRUE((*pieces)->Render(camera, &split).ok());
    ASSERT_EQ(split.size(), whole.size());
    EXPECT_GT(CountFinite(whole), 1000);
    int mismatches = 0;
    for (size_t i = 0; i < whole.size(); ++i) {
      // Pieces use their own matrices, so depths may differ by rounding, coverage may not.
      const bool same = std::isinf(whole[i]) ? std::isinf(split[i])
                                             : std::abs(split[i] - whole[i]) <= 1e-5 * whole[i];
      if (!same && ++mismatches <= 5) {
        ADD_FAILURE() << "texel " << i % camera.window.width << ", " << i / camera.window.width
                      << ": split " << split[i] << " whole " << whole[i];
      }
    }
    EXPECT_EQ(mismatches, 0);
  }
}

// (7) A window wider than the 8192 cap is stitched from pieces; coverage stays texel-exact.
TEST_F(ShadowMapRendererTest, WindowWiderThanLimitIsRenderedInPieces) {
  Mesh mesh;
  mesh.AddParallelQuad(0, 2700, 0, 1, 5);  // s in [0, 540], t in [0, 0.2]
  Upload(mesh);
  ShadowMapCamera camera = TestCamera();
  // s in [-2.01, 560.49): the first piece ends at s = 509.99, inside the quad.
  camera.window = {.x0 = 0, .y0 = 0, .width = 9000, .height = 16};
  camera.lattice.t_origin = -0.52;  // t in [-0.52, 0.48)
  const std::vector<float> depth = RenderOrDie(camera);
  ExpectDepths(camera, depth, [](double s, double t) {
    return Inside(s, 0, 540) && Inside(t, 0, 0.2) ? 5.0 : INFINITY;
  });
  EXPECT_GT(CountFinite(depth), 0);
}

// (8) Same camera and geometry: bit-identical, whatever was rendered in between.
TEST_F(ShadowMapRendererTest, RepeatedRendersAreBitIdentical) {
  const Mesh mesh = BusyScene();
  Upload(mesh);
  ShadowMapCamera camera = TestCamera();
  camera.sample = {0.3, 0.2};
  camera.slope_bias = 1;
  const std::vector<float> first = RenderOrDie(camera);
  ShadowMapCamera wider = camera;
  wider.window.width = 200;  // grows the cached target
  const std::vector<float> wider_first = RenderOrDie(wider);
  EXPECT_TRUE(BitIdentical(RenderOrDie(camera), first));
  EXPECT_TRUE(BitIdentical(RenderOrDie(camera), first));
  // The same bits from a fresh renderer, whose target never held the smaller window.
  absl::StatusOr<std::unique_ptr<ShadowMapRenderer>> fresh = ShadowMapRenderer::Create();
  ASSERT_TRUE(fresh.ok()) << fresh.status();
  ASSERT_TRUE((*fresh)->SetGeometry(mesh.positions, mesh.indices).ok());
  std::vector<float> from_fresh;
  ASSERT_TRUE((*fresh)->Render(wider, &from_fresh).ok());
  EXPECT_TRUE(BitIdentical(from_fresh, wider_first));
  ASSERT_TRUE((*fresh)->Render(camera, &from_fresh).ok());
  EXPECT_TRUE(BitIdentical(from_fresh, first));
}

// (9) Alpha-tested ranges (core/scene/alpha_mask.h): a quad at z = 5 over s, t in [0, 2.1]
// whose mask is opaque on its left half (u < 1/2, s < 1.05) and clear on its right, drawn with
// an opaque quad behind it at z = 8: through the hole the map reads the quad behind.
TEST_F(ShadowMapRendererTest, AlphaTestedRangesCoverOnlyWhereTheirMaskPasses) {
  Mesh mesh;
  mesh.AddParallelQuad(0, 10.5, 0, 10.5, 5);  // triangles 0, 1: the card
  mesh.AddParallelQuad(0, 16.8, 0, 16.8, 8);  // triangles 2, 3: behind it, the same s, t
  std::vector<glm::vec2> uvs;
  for (const glm::vec3& p : mesh.positions) uvs.emplace_back(p.x / 10.5f, p.y / 10.5f);
  ASSERT_TRUE(renderer_->SetGeometry(mesh.positions, mesh.indices, uvs).ok());
  auto mask = std::make_shared<AlphaMask>();
  mask->width = 2;
  mask->height = 1;
  mask->alpha = {255, 0};
  mask->wrap_u = mask->wrap_v = TextureWrap::kClampToEdge;
  const std::shared_ptr<const AlphaMask> masks[] = {mask};
  ASSERT_TRUE(renderer_->SetMasks(masks).ok());
  const ShadowMapCamera camera = TestCamera();
  const DrawRange card_and_back[] = {{0, 2, 1}, {2, 2, 0}};
  std::vector<float> depth;
  ASSERT_TRUE(renderer_->Render(camera, card_and_back, &depth).ok());
  // Texels within one of s = 1.05 are not checked: the filtered alpha crosses 1/2 there.
  ExpectDepths(camera, depth, [](double s, double t) -> double {
    if (!Inside(t, 0, 2.1) || !Inside(s, 0, 2.1)) return INFINITY;
    if (std::abs(s - 1.05) < 0.0625) return NAN;
    return s < 1.05 ? 5.0 : 8.0;
  });
  // Opaque, the same card covers its whole square.
  const DrawRange opaque_card[] = {{0, 2, 0}};
  ASSERT_TRUE(renderer_->Render(camera, opaque_card, &depth).ok());
  ExpectDepths(camera, depth, [](double s, double t) {
    return Inside(s, 0, 2.1) && Inside(t, 0, 2.1) ? 5.0 : INFINITY;
  });
  // A mask past those set, or masks without UVs, are refused.
  const DrawRange second_mask[] = {{0, 2, 2}};
  EXPECT_EQ(renderer_->Render(camera, second_mask, &depth).code(),
            absl::StatusCode::kInvalidArgument);
  ASSERT_TRUE(renderer_->SetGeometry(mesh.positions, mesh.indices).ok());
  EXPECT_EQ(renderer_->Render(camera, card_and_back, &depth).code(),
            absl::StatusCode::kInvalidArgument);
  // A UV count that is not the position count is refused, as is an invalid mask.
  uvs.pop_back();
  EXPECT_EQ(renderer_->SetGeometry(mesh.positions, mesh.indices, uvs).code(),
            absl::StatusCode::kInvalidArgument);
  mask->cutoff = 0;
  EXPECT_EQ(renderer_->SetMasks(masks).code(), absl::StatusCode::kInvalidArgument);
}

// (8) Renderers on two threads at once give the same bits as one on the test thread.
TEST_F(ShadowMapRendererTest, RenderersOnTwoThreads) {
  const Mesh mesh = BusyScene();
  Upload(mesh);
  ShadowMapCamera camera = TestCamera();
  camera.sample = {-0.4, 0.25};
  camera.slope_bias = 2;
  const std::vector<float> reference = RenderOrDie(camera);
  std::vector<float> results[2];
  absl::Status statuses[2];
  std::vector<std::thread> threads;
  for (int i = 0; i < 2; ++i) {
    threads.emplace_back([&, i] {
      absl::StatusOr<std::unique_ptr<ShadowMapRenderer>> renderer = ShadowMapRenderer::Create();
      if (!renderer.ok()) {
        statuses[i] = renderer.status();
        return;
      }
      statuses[i] = (*renderer)->SetGeometry(mesh.positions, mesh.indices);
      for (int k = 0; k < 5 && statuses[i].ok(); ++k) {
        statuses[i] = (*renderer)->Render(camera, &results[i]);
        if (statuses[i].ok() && !BitIdentical(results[i], reference)) {
          statuses[i] = absl::InternalError("differs from the reference");
        }
      }
    });
  }
  for (std::thread& thread : threads) thread.join();
  for (int i = 0; i < 2; ++i) EXPECT_TRUE(statuses[i].ok()) << statuses[i];
  // This thread's renderer still works after the others came and went.
  EXPECT_TRUE(BitIdentical(RenderOrDie(camera), reference));
}

// Two renderers interleaved on one thread: each makes its own context current.
TEST_F(ShadowMapRendererTest, TwoRenderersOnOneThread) {
  absl::StatusOr<std::unique_ptr<ShadowMapRenderer>> second = ShadowMapRenderer::Create();
  ASSERT_TRUE(second.ok()) << second.status();
  Mesh near_quad, far_quad;
  near_quad.AddParallelQuad(0, 10, 0, 10, 5);
  far_quad.AddParallelQuad(0, 20, 0, 20, 10);
  Upload(near_quad);
  ASSERT_TRUE((*second)->SetGeometry(far_quad.positions, far_quad.indices).ok());
  const ShadowMapCamera camera = TestCamera();
  std::vector<float> from_second;
  ASSERT_TRUE((*second)->Render(camera, &from_second).ok());
  const ExpectedDepth in_square = [](double s, double t) {
    return Inside(s, 0, 2) && Inside(t, 0, 2) ? 1.0 : INFINITY;
  };
  ExpectDepths(camera, RenderOrDie(camera),
               [&](double s, double t) { return 5 * in_square(s, t); });
  ExpectDepths(camera, from_second, [&](double s, double t) { return 10 * in_square(s, t); });
  second->reset();  // destroying it must not disturb this renderer
  ExpectDepths(camera, RenderOrDie(camera),
               [&](double s, double t) { return 5 * in_square(s, t); });
}

// (9) No casters: every texel is +inf, also after geometry is replaced by nothing.
TEST_F(ShadowMapRendererTest, EmptyGeometryGivesInfinity) {
  const ShadowMapCamera camera = TestCamera();
  ExpectDepths(camera, RenderOrDie(camera), [](double, double) { return INFINITY; });
  Upload(BusyScene());
  EXPECT_GT(CountFinite(RenderOrDie(camera)), 0);
  Upload(Mesh{});
  ExpectDepths(camera, RenderOrDie(camera), [](double, double) { return INFINITY; });
}

TEST_F(ShadowMapRendererTest, EmptyWindowGivesEmptyOutput) {
  ShadowMapCamera camera = TestCamera();
  camera.window.width = 0;
  std::vector<float> depth(3, 1.0f);
  ASSERT_TRUE(renderer_->Render(camera, &depth).ok());
  EXPECT_TRUE(depth.empty());
}

TEST_F(ShadowMapRendererTest, RejectsBadInput) {
  const std::vector<glm::vec3> positions = {{0, 0, 1}, {1, 0, 1}, {0, 1, 1}};
  const std::vector<uint32_t> out_of_range = {0, 1, 3};
  EXPECT_EQ(renderer_->SetGeometry(positions, out_of_range).code(),
            absl::StatusCode::kInvalidArgument);
  const std::vector<uint32_t> not_triangles = {0, 1};
  EXPECT_EQ(renderer_->SetGeometry(positions, not_triangles).code(),
            absl::StatusCode::kInvalidArgument);
  const std::vector<glm::vec3> nan_position = {{0, 0, NAN}, {1, 0, 1}, {0, 1, 1}};
  EXPECT_EQ(renderer_->SetGeometry(nan_position, std::vector<uint32_t>{0, 1, 2}).code(),
            absl::StatusCode::kInvalidArgument);

  std::vector<float> depth;
  ShadowMapCamera camera = TestCamera();
  camera.z_clip_near = 0;
  EXPECT_EQ(renderer_->Render(camera, &depth).code(), absl::StatusCode::kInvalidArgument);
  camera = TestCamera();
  camera.projection = Projection::kOrthographic;
  camera.z_clip_far = camera.z_clip_near;
  EXPECT_EQ(renderer_->Render(camera, &depth).code(), absl::StatusCode::kInvalidArgument);
  camera = TestCamera();
  camera.lattice.pitch_t = 0;
  EXPECT_EQ(renderer_->Render(camera, &depth).code(), absl::StatusCode::kInvalidArgument);
  ShadowMapRenderer::Options options;
  options.max_piece_size = 1;
  EXPECT_EQ(ShadowMapRenderer::Create(options).status().code(), absl::StatusCode::kInvalidArgument);
}

// The bias chunk is embedded with the shader (GLSL has no #include): no #include line is left
// for the driver, and BiasedDepth is defined once.
TEST(ShadowMapShadersTest, BiasChunkIsIncludedAtBuildTime) {
  const std::string fragment = kShadowMapFragmentShader;
  EXPECT_FALSE(std::regex_search(fragment, std::regex("(^|\n)[ \t]*#[ \t]*include"))) << fragment;
  const size_t definition = fragment.find("float BiasedDepth(");
  ASSERT_NE(definition, std::string::npos) << fragment;
  EXPECT_EQ(fragment.find("float BiasedDepth(", definition + 1), std::string::npos);
}

// Not a test: a timing probe (run with --gtest_also_run_disabled_tests). A 512x512 shadow map
// of a ~200k-triangle height-field grid.
TEST_F(ShadowMapRendererTest, DISABLED_Timing512Grid200k) {
  Mesh mesh;
  constexpr int kCells = 317;  // 2 * 317^2 = 200978 triangles
  for (int j = 0; j <= kCells; ++j) {
    for (int i = 0; i <= kCells; ++i) {
      const float x = -10 + 20.0f * i / kCells, y = -10 + 20.0f * j / kCells;
      mesh.positions.push_back({x, y, 5 + 0.5f * std::sin(x) * std::cos(y)});
    }
  }
  for (int j = 0; j < kCells; ++j) {
    for (int i = 0; i < kCells; ++i) {
      const uint32_t v = j * (kCells + 1) + i;
      mesh.indices.insert(mesh.indices.end(),
                          {v, v + 1, v + kCells + 2, v, v + kCells + 2, v + kCells + 1});
    }
  }
  Upload(mesh);
  ShadowMapCamera camera;
  camera.lattice = {.s_origin = -2, .t_origin = -2, .pitch_s = 4.0 / 512, .pitch_t = 4.0 / 512};
  camera.window = {.x0 = 0, .y0 = 0, .width = 512, .height = 512};
  camera.z_clip_near = 0.5;
  camera.slope_bias = 1;
  RenderOrDie(camera);  // warm-up: first draw compiles the llvmpipe shader variant
  constexpr int kRuns = 10;
  const auto start = std::chrono::steady_clock::now();
  for (int k = 0; k < kRuns; ++k) {
    camera.sample = {0.01 * k, 0};
    RenderOrDie(camera);
  }
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  std::printf("512x512, %zu triangles: %.2f ms per render\n", mesh.indices.size() / 3, ms / kRuns);
  EXPECT_GT(CountFinite(RenderOrDie(camera)), 512 * 512 / 2);
}

}  // namespace
}  // namespace pdsm
