// Objects added at view time cast in the PDSM modes (thesis 4.3's complementary method): a few
// shadow maps of the dynamic objects alone, combined with the baked attenuation. Measured here
// against the Embree reference of the full scene (the bake's meshes plus the dynamic object),
// at the very ground points the frame shaded; docs/viewer.md ("Dynamic objects") quotes the
// printed table.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "client/view/frame_renderer.h"
#include "client/view/view_scene.h"
#include "core/pdsm/pdsm_file.h"
#include "core/reference/embree_visibility.h"
#include "gl/gl_functions.h"
#include "gl/platform/osmesa_context.h"
#include "tests/view/view_test_support.h"

namespace pdsm::testing {
namespace {

constexpr int kWidth = 240, kHeight = 180;
const view::Camera kCamera{{4, 7, 6}, {0, 1, 0}, 40};

// plates baked finer than SmallBake, so that the bake's own error stays below what is measured.
std::string PlatesBake() {
  static const std::string* path =
      new std::string(BakeExample("plates", "plates_dynamic.exr", 128, 64, 512));
  return *path;
}

// A dynamic object's triangles as a caster of the reference scene (world space).
TriangleMesh WorldMesh(const view::DynamicObject& object) {
  TriangleMesh mesh;
  mesh.label = "dynamic";
  for (const glm::vec3& p : object.mesh.positions) {
    mesh.indices.push_back(static_cast<uint32_t>(mesh.positions_world.size()));
    mesh.positions_world.push_back(glm::dvec3(object.world_from_object * glm::dvec4(p, 1.0)));
  }
  return mesh;
}

struct Errors {
  double shadowed = 0;  // mean |A - A_ref| where the dynamic object matters (see Measure)
  double overlap = 0;   // the same where baked and dynamic shadows both are above 0.02
  size_t n_shadowed = 0, n_overlap = 0;
};

struct Measurement {
  Errors baked_only, max, product;
};

// Other map counts and sizes, product combination: what the default buys against them.
struct MapsConfig {
  int count, size;
};
constexpr MapsConfig kConfigs[] = {{16, 512}, {32, 512}, {32, 1024}, {64, 1024}};

// Renders `object` over plates in pdsm mode three ways (no dynamic shadow, max, product) and
// measures each on the ground pixels against Embree (1024 samples per point, mean error
// 0.00016: docs/accuracy.md) of the full scene.
Measurement Measure(view::DynamicObject object) {
  view::ViewScene view;
  absl::StatusOr<Scene> scene = LoadSceneFile(ExamplePath("plates"));
  absl::StatusOr<PdsmImage> pdsm = ReadPdsm(PlatesBake());
  EXPECT_TRUE(scene.ok() && pdsm.ok());
  if (!scene.ok() || !pdsm.ok()) return {};
  view.scene = *scene;
  view.pdsm = view::PdsmTiles::FromImage(*std::move(pdsm));
  view::PrepareViewScene(&view);
  view.dynamic_objects.push_back(object);

  absl::StatusOr<gl::OsMesaContext> context = gl::OsMesaContext::Create();
  EXPECT_TRUE(context.ok()) << context.status();
  if (!context.ok()) return {};
  absl::StatusOr<gl::GlFunctions> gl = gl::GlFunctions::Load(&gl::OsMesaContext::GetProcAddress);
  EXPECT_TRUE(gl.ok());
  std::vector<float> positions, baked, max, product;
  std::vector<std::vector<float>> configs;
  for (const MapsConfig& c : kConfigs) {
    view::RenderSettings settings;
    settings.dynamic_sm_count = c.count;
    settings.dynamic_sm_size = c.size;
    settings.dynamic_combine = view::DynamicCombine::kProduct;
    absl::StatusOr<std::unique_ptr<view::FrameRenderer>> r =
        view::FrameRenderer::Create(*gl, &view, settings);
    EXPECT_TRUE(r.ok() && (*r)->Render(view::ViewMode::kPdsm, kCamera, kWidth, kHeight).ok());
    absl::StatusOr<view::Frame> frame = (*r)->ReadFrame();
    configs.push_back(frame.ok() ? frame->attenuation : std::vector<float>());
  }
  {
    absl::StatusOr<std::unique_ptr<view::FrameRenderer>> renderer =
        view::FrameRenderer::Create(*gl, &view, view::RenderSettings{});
    EXPECT_TRUE(renderer.ok()) << renderer.status();
    if (!renderer.ok()) return {};
    view::FrameRenderer& r = **renderer;
    const auto render = [&](bool dynamic, view::DynamicCombine combine) {
      r.settings().dynamic_shadows = dynamic;
      r.settings().dynamic_combine = combine;
      EXPECT_TRUE(r.Render(view::ViewMode::kPdsm, kCamera, kWidth, kHeight).ok());
      absl::StatusOr<view::Frame> frame = r.ReadFrame();
      EXPECT_TRUE(frame.ok());
      return frame.ok() ? frame->attenuation : std::vector<float>();
    };
    baked = render(false, view::DynamicCombine::kMax);
    max = render(true, view::DynamicCombine::kMax);
    product = render(true, view::DynamicCombine::kProduct);
    absl::StatusOr<std::vector<float>> p = r.ReadPositions(kCamera, kWidth, kHeight);
    EXPECT_TRUE(p.ok());
    if (p.ok()) positions = *std::move(p);
  }
  // Ground pixels (y = 0, inside the 20 x 20 receiver), snapped onto the plane: the reference
  // must see the point on its surface, not a float rounding below it.
  std::vector<glm::dvec3> points;
  std::vector<size_t> pixels;
  for (size_t i = 0; i < baked.size(); i += 2) {
    if (positions[4 * i + 3] != 1.0f || baked[i] < 0) continue;
    glm::dvec3 world = view.frame().WorldFromLight(
        glm::dvec3(positions[4 * i], positions[4 * i + 1], positions[4 * i + 2]));
    if (std::abs(world.y) > 1e-3 || std::abs(world.x) > 9.9 || std::abs(world.z) > 9.9) continue;
    world.y = 0;
    points.push_back(world);
    pixels.push_back(i);
  }
  Scene full = *scene;
  full.meshes.push_back(WorldMesh(object));
  absl::StatusOr<std::vector<double>> reference = EmbreeAttenuation(full, points, 1024);
  EXPECT_TRUE(reference.ok()) << reference.status();
  EXPECT_GT(points.size(), 2000u);
  if (!reference.ok()) return {};
  Measurement m;
  std::vector<Errors> config_errors(std::size(kConfigs));
  const auto add = [](Errors* e, double value, double ref, bool overlap) {
    e->shadowed += std::abs(value - ref);
    ++e->n_shadowed;
    if (overlap) {
      e->overlap += std::abs(value - ref);
      ++e->n_overlap;
    }
  };
  for (size_t k = 0; k < points.size(); ++k) {
    const size_t i = pixels[k];
    const double ref = (*reference)[k];
    // The dynamic shadow alone, recovered from the product: 1 - (1 - b)(1 - d) = p.
    const double dynamic = baked[i] < 0.999 ? (product[i] - baked[i]) / (1.0 - baked[i]) : 0.0;
    const bool overlap = baked[i] > 0.02 && dynamic > 0.02;
    // Where the object matters: its own shadow, or where the reference (which has it) and the
    // bake (which has not) disagree.
    if (!(dynamic > 0.01 || std::abs(ref - baked[i]) > 0.02)) continue;
    add(&m.baked_only, baked[i], ref, overlap);
    add(&m.max, max[i], ref, overlap);
    add(&m.product, product[i], ref, overlap);
    for (size_t c = 0; c < configs.size(); ++c) add(&config_errors[c], configs[c][i], ref, overlap);
  }
  for (size_t c = 0; c < configs.size(); ++c) {
    std::printf("  product, %d maps of %d^2: %.4f where it matters, %.4f where they overlap\n",
                kConfigs[c].count, kConfigs[c].size,
                config_errors[c].shadowed / std::max<size_t>(config_errors[c].n_shadowed, 1),
                config_errors[c].overlap / std::max<size_t>(config_errors[c].n_overlap, 1));
  }
  for (Errors* e : {&m.baked_only, &m.max, &m.product}) {
    e->shadowed /= std::max<size_t>(e->n_shadowed, 1);
    e->overlap /= std::max<size_t>(e->n_overlap, 1);
  }
  std::printf(
      "%zu ground points; mean |A - A_embree| where the object matters (n=%zu): baked only "
      "%.4f, max %.4f, product %.4f; where baked and dynamic shadows overlap (n=%zu): baked "
      "only %.4f, max %.4f, product %.4f\n",
      points.size(), m.max.n_shadowed, m.baked_only.shadowed, m.max.shadowed, m.product.shadowed,
      m.max.n_overlap, m.baked_only.overlap, m.max.overlap, m.product.overlap);
  return m;
}

// The default (RenderSettings) must be what measures best, and casting must pay off.
void ExpectDefaultIsBest(const Measurement& m) {
  const view::DynamicCombine chosen = view::RenderSettings{}.dynamic_combine;
  const Errors& best = chosen == view::DynamicCombine::kMax ? m.max : m.product;
  const Errors& other = chosen == view::DynamicCombine::kMax ? m.product : m.max;
  EXPECT_LT(best.shadowed, 0.5 * m.baked_only.shadowed) << "the dynamic shadow barely helps";
  EXPECT_LE(best.shadowed, other.shadowed) << "the other combination measures better";
  EXPECT_LE(best.overlap, other.overlap) << "the other combination measures better";
  EXPECT_GT(best.n_overlap, 50u) << "the object's shadow should overlap a baked one";
}

// A sphere beside the bar and under the triangle: its shadow crosses theirs.
TEST(ViewDynamicShadows, SphereMeasuredAgainstEmbreeOfTheFullScene) {
  view::DynamicObject sphere;
  sphere.mesh = view::MakeUnitSphere();
  sphere.world_from_object = glm::dmat4(0.5);
  sphere.world_from_object[3] = glm::dvec4(1.0, 1.2, 1.5, 1.0);
  ExpectDefaultIsBest(Measure(sphere));
}

// A mesh file (--object): a box on stilts of its own, its shadow overlapping the square's.
TEST(ViewDynamicShadows, MeshMeasuredAgainstEmbreeOfTheFullScene) {
  TempDir dir;
  WriteText(dir.File("box.obj"),
            "v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\n"
            "v -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n"
            "f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\n"
            "f 4 8 7\nf 4 7 3\nf 1 5 8\nf 1 8 4\nf 2 3 7\nf 2 7 6\n");
  absl::StatusOr<view::DrawMesh> box = view::LoadObjectMesh(dir.File("box.obj"), "--object[0]");
  ASSERT_TRUE(box.ok()) << box.status();
  view::DynamicObject object;
  object.mesh = *box;
  object.world_from_object = glm::dmat4(0.4);
  object.world_from_object[3] = glm::dvec4(-0.5, 1.6, 0.8, 1.0);
  ExpectDefaultIsBest(Measure(object));
}

}  // namespace
}  // namespace pdsm::testing
