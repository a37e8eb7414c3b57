#include "core/bake/bake_plan.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "absl/strings/str_format.h"
#include "core/bake/caster_culling.h"
#include "core/bake/face_samples.h"
#include "core/bake/level_groups.h"
#include "core/bake/refined_pixels.h"
#include "core/bake/tile_reach.h"
#include "core/bake/window_fit.h"
#include "core/sampling/light_samples.h"

namespace pdsm {
namespace {

// What a plan reads of a scene: its index (the meshes, referred to, never copied: a world's
// are tens of MB, and a job plans each of its lights), its names, and the one light it bakes
// with that light's settings. The members are named as Scene's.
struct PlanInput {
  const SceneIndex& index;
  const std::string& name;
  const std::string& source_path;
  const LightSpec& light;
  const BakeSettings& bake;
  const std::string& light_name;
};

// Sun: the frame's centre is placed so that the whole scene lies at z in (0, 2R].
LightFrame SunFrame(const PlanInput& scene) {
  LightFrame frame = scene.light.frame;
  if (scene.index.empty()) {
    frame.center = -frame.n;
    return frame;
  }
  const glm::dvec3 mid = 0.5 * (scene.index.lo() + scene.index.hi());
  const double radius = std::max(0.5 * glm::length(scene.index.hi() - scene.index.lo()), 1e-9);
  frame.center = mid - (radius * 1.01) * frame.n;
  return frame;
}

void MakeTiles(BakePlan* plan) {
  const PdsmGeometry& g = plan->header.geometry;
  const int size = plan->header.tile_size;
  plan->tiles_x = (g.width + size - 1) / size;
  plan->tiles_y = (g.height + size - 1) / size;
}

void FillHeader(const PlanInput& scene, BakePlan* plan) {
  PdsmHeader& h = plan->header;
  h.scene_name = scene.name;
  h.light_name = scene.light_name;
  h.light_shape = scene.light.shape;
  h.light_half_width = scene.light.half_width;
  h.light_half_height = scene.light.half_height;
  h.light_radius = scene.light.radius;
  h.cone_half_angle_deg = scene.light.cone_half_angle_deg;
  h.face_tangent = scene.light.face_tangent;
  h.tan_half_angle = scene.light.tan_half_angle;
  h.samples = scene.bake.samples;
  h.shadow_map_resolution = scene.bake.shadow_map_resolution;
  h.epsilon = scene.bake.epsilon;
  h.compression_metric = scene.bake.compression_metric;
  h.weighting = scene.bake.weighting;
  h.slope_bias = scene.bake.slope_bias;
  h.sampling = scene.bake.sampling;
  h.seed = scene.bake.seed;
  if (scene.bake.adaptive()) {
    h.adaptive_tolerance = scene.bake.adaptive_tolerance;
    h.adaptive_min_samples = scene.bake.adaptive_min_samples;
  }
  h.tile_size = scene.bake.tile_size;
  h.surfaces_only = scene.bake.surfaces_only;
  h.max_refinement = scene.bake.max_refinement;
}

// The nearest depth perspective rays are scanned from (docs/algorithms.md, "Depth range"):
// a ray's segment in sample (a, b)'s shadow map spans |a| w / pitch texels from w = 1/z to
// the far end, so a tile's window is about (X + alpha w)(Y + beta w) texels, X and Y the
// tile's own extent. The floor is the deeper of
//  - the depth where that reaches the texel budget for the widest sample (memory), and
//  - the depth where one ray crosses kMaxRayTexels texels per axis (time), but never deeper
//    than half the nearest receiver's depth: the receivers stay resolved.
// Nearer points are not resolved. 0 when there is no limit (a point light).
double ScanFloor(const BakePlan& plan, double z_near_receivers) {
  const PdsmGeometry& g = plan.header.geometry;
  if (g.projection != Projection::kPerspective) return 0;
  double a_max = 0, b_max = 0;
  for (const glm::dvec2& sample : plan.samples) {
    a_max = std::max(a_max, std::abs(sample.x));
    b_max = std::max(b_max, std::abs(sample.y));
  }
  a_max *= FaceSampleStretch(plan);  // a sphere face's groups stretch them
  b_max *= FaceSampleStretch(plan);
  const double tile = plan.header.tile_size;
  const double x = tile * g.PixelPitchS() / plan.lattice.pitch_s + 2;
  const double y = tile * g.PixelPitchT() / plan.lattice.pitch_t + 2;
  const double budget = std::min(static_cast<double>(kMaxShadowMapTexels),
                                 std::max(static_cast<double>(kShadowMapTexelBudget), 4 * x * y));
  const double alpha = a_max / plan.lattice.pitch_s, beta = b_max / plan.lattice.pitch_t;
  // Positive root of alpha beta w^2 + (alpha y + beta x) w + x y - budget = 0, in the form
  // that stays finite when alpha beta = 0.
  const double c = budget - x * y;
  const double l = alpha * y + beta * x;
  if (!(c > 0) || !(l > 0)) return 0;
  const double w = 2 * c / (l + std::sqrt(l * l + 4 * alpha * beta * c));
  const double memory_floor = 1.0 / w;
  double time_floor = std::max(alpha, beta) / kMaxRayTexels;
  if (std::isfinite(z_near_receivers)) time_floor = std::min(time_floor, 0.5 * z_near_receivers);
  return std::max(memory_floor, time_floor);
}

// The window from a fit. A margin of 1e-3 of the window keeps silhouettes on the border
// inside it.
void SetWindow(const WindowFit& fit, PdsmGeometry* g) {
  const double ms = 1e-3 * std::max(fit.s_hi - fit.s_lo, 1e-9);
  const double mt = 1e-3 * std::max(fit.t_hi - fit.t_lo, 1e-9);
  g->s_min = fit.s_lo - ms;
  g->s_max = fit.s_hi + ms;
  g->t_min = fit.t_lo - mt;
  g->t_max = fit.t_hi + mt;
}

// The global shadow-map lattice: square texels, shadowMapResolution across the window.
void SetLattice(const PlanInput& scene, BakePlan* plan) {
  const PdsmGeometry& g = plan->header.geometry;
  const double texel_pitch =
      std::max(g.s_max - g.s_min, g.t_max - g.t_min) / scene.bake.shadow_map_resolution;
  plan->lattice = ShadowMapLattice{g.s_min, g.t_min, texel_pitch, texel_pitch};
}

}  // namespace

double DefaultDepthBias(double z_far) { return 1e-5 * std::abs(z_far); }

double MaxWindowTangent(const LightSpec& light) {
  if (light.is_sphere_face()) return std::min(kMaxWindowTangent, light.face_tangent);
  if (!light.is_spot()) return kMaxWindowTangent;
  return std::min(kMaxWindowTangent, std::tan(light.cone_half_angle_deg * std::numbers::pi / 180));
}

namespace {

absl::StatusOr<BakePlan> PlanLight(const PlanInput& scene, PlanCasters casters) {
  BakePlan plan;
  FillHeader(scene, &plan);
  PdsmGeometry& g = plan.header.geometry;
  g.projection =
      scene.light.shape == LightShape::kSun ? Projection::kOrthographic : Projection::kPerspective;
  g.frame = g.projection == Projection::kOrthographic ? SunFrame(scene) : scene.light.frame;
  g.width = scene.bake.width;
  g.height = scene.bake.height;

  // Fit the frustum to what lies in front of the light.
  const SceneIndex& index = scene.index;
  const double scene_size =
      index.empty() ? 1.0 : std::max(glm::length(index.hi() - index.lo()), 1e-30);
  const double z_min_fit = 1e-6 * scene_size;
  const WindowFit fit = FitIndexed(index, FitRequest{scene.light, g, z_min_fit});

  if (scene.bake.frustum) {
    const FrustumOverride& f = *scene.bake.frustum;
    g.s_min = f.s_min;
    g.s_max = f.s_max;
    g.t_min = f.t_min;
    g.t_max = f.t_max;
    g.z_near = f.z_near;
    g.z_far = f.z_far;
    if (g.projection == Projection::kPerspective && !(f.z_near > 0)) {
      return absl::InvalidArgumentError(
          absl::StrFormat("%s: bake.frustum.depthRange[0]: must be > 0 for a %s light (got %g)",
                          scene.source_path, "rect or disk", f.z_near));
    }
  } else if (fit.empty()) {
    g.s_min = g.t_min = -1;
    g.s_max = g.t_max = 1;
    g.z_near = 1;
    g.z_far = 2;
  } else {
    SetWindow(fit, &g);
    g.z_far = fit.z_far_all;
    g.z_near = std::isfinite(fit.z_near_casters) ? fit.z_near_casters : fit.z_far_all;
  }

  plan.header.depth_bias = scene.bake.depth_bias.value_or(DefaultDepthBias(g.z_far));
  // Nothing nearer than the nearest caster can shadow; clip a hair in front of it.
  plan.z_clip_near = g.projection == Projection::kPerspective
                         ? g.z_near * (1.0 - 1e-6)
                         : g.z_near - 1e-6 * std::max(std::abs(g.z_far - g.z_near), 1e-9);
  plan.z_clip_far = g.z_far + 1e-3 * std::max(g.z_far - g.z_near, 1e-9);

  SetLattice(scene, &plan);
  plan.samples =
      GenerateLightSamples(scene.light, scene.bake.samples, scene.bake.sampling, scene.bake.seed);
  MakeTiles(&plan);
  plan.z_scan_floor = ScanFloor(plan, fit.z_near_receivers);
  const double z_nearest_anywhere =
      std::isfinite(fit.z_near_casters_anywhere) ? fit.z_near_casters_anywhere : fit.z_far_all;
  if (!scene.bake.frustum && plan.z_scan_floor > std::min(g.z_near, z_nearest_anywhere)) {
    // Casters nearer than the floor (within about 1e-3 of the light plane) would stretch the
    // fitted window towards tan 85 degrees, leaving the receivers a few pixels. Fit it to what
    // lies beyond the floor: the receivers (their whole extent) when there are any. (Such a
    // caster may lie where it shadows nothing in the window, and so not be z_near: it still
    // stretched the window.)
    const WindowFit refit =
        FitIndexed(index, FitRequest{scene.light, g, plan.z_scan_floor, /*receivers_only=*/true});
    if (!refit.empty()) {
      SetWindow(refit, &g);
      SetLattice(scene, &plan);
      plan.z_scan_floor = std::max(plan.z_scan_floor, ScanFloor(plan, fit.z_near_receivers));
    }
  }
  // Casters nearer than the floor still shadow what lies beyond it (they are drawn), but
  // points nearer than it are outside what the PDSM resolves: queries there are NaN.
  if (plan.z_scan_floor > g.z_near) g.z_valid_min = plan.z_scan_floor;
  plan.header.format_version = MinimumFormatVersion(plan.header);
  plan.tile_group_size = scene.bake.tile_group_size;
  plan.group_side = GroupSideInTiles(plan);
  GatherCasters(index, casters, &plan);
  // Only a surfaces-only bake (its depth windows) and a refined one (the bands of its refined
  // pixels) use the receivers; the light-view preview adds them (AddLightSpaceReceivers).
  if (plan.header.surfaces_only || plan.header.max_refinement > 1) {
    AddLightSpaceReceivers(index.scene(), &plan);
  }
  return plan;
}

}  // namespace

absl::StatusOr<BakePlan> PlanBake(const SceneIndex& index, PlanCasters casters) {
  const Scene& scene = index.scene();
  return PlanLight(
      PlanInput{index, scene.name, scene.source_path, scene.light, scene.bake, scene.light_name},
      casters);
}

absl::StatusOr<BakePlan> PlanBake(const SceneIndex& index, size_t light, PlanCasters casters) {
  const Scene& scene = index.scene();
  const SceneLight one = LightOf(scene, light);
  return PlanLight(PlanInput{index, scene.name, scene.source_path, one.spec, one.bake, one.name},
                   casters);
}

absl::StatusOr<BakePlan> PlanBake(const Scene& scene, PlanCasters casters) {
  absl::StatusOr<std::shared_ptr<const SceneIndex>> index = SceneIndex::Build(scene);
  if (!index.ok()) return index.status();
  return PlanBake(**index, casters);
}

absl::StatusOr<BakePlan> PlanBake(const Scene& scene, size_t light, PlanCasters casters) {
  absl::StatusOr<std::shared_ptr<const SceneIndex>> index = SceneIndex::Build(scene);
  if (!index.ok()) return index.status();
  return PlanBake(**index, light, casters);
}

absl::StatusOr<BakePlan> PlanRefinementLevel(const SceneIndex& index, std::optional<size_t> light,
                                             const BakePlan& base,
                                             std::shared_ptr<const RefinedPixels> refined) {
  const int factor = refined->factor();
  const Scene& scene = index.scene();
  const SceneLight one = light ? LightOf(scene, *light) : SceneLight{};
  const LightSpec& spec = light ? one.spec : scene.light;
  BakeSettings bake = light ? one.bake : scene.bake;
  const std::string& name = light ? one.name : scene.light_name;
  const PdsmGeometry& g = base.header.geometry;
  const int64_t width = int64_t{g.width} * factor, height = int64_t{g.height} * factor;
  const int64_t sm = int64_t{bake.shadow_map_resolution} * factor;
  const int64_t tile = std::max(1, bake.tile_size);
  const int64_t tiles = ((width + tile - 1) / tile) * ((height + tile - 1) / tile);
  // The level's shadow maps are windows of its lattice like any bake's (their texels are
  // bounded per window), so only the map itself is held to the limits.
  if (width > kMaxPdsmResolution || height > kMaxPdsmResolution ||
      width * height > kMaxPdsmPixels || tiles > kMaxPdsmTiles) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "%s: bake.maxRefinement: refining %dx%d pixels %d times makes a %dx%d map of %d "
        "tiles, past a map's limits (%d a side, %d pixels, %d tiles): lower maxRefinement or "
        "resolution",
        scene.source_path, g.width, g.height, factor, width, height, tiles, kMaxPdsmResolution,
        kMaxPdsmPixels, kMaxPdsmTiles));
  }
  bake.width = static_cast<int>(width);
  bake.height = static_cast<int>(height);
  bake.shadow_map_resolution = static_cast<int>(sm);
  bake.max_refinement = 1;
  bake.surfaces_only = false;
  // The base's frustum exactly, as fitted: the level's pixels subdivide the base's.
  bake.frustum = FrustumOverride{g.s_min, g.s_max, g.t_min, g.t_max, g.z_near, g.z_far};
  // The base's bias as applied (a default one follows z_far, which the frustum keeps).
  bake.depth_bias = base.header.depth_bias;
  absl::StatusOr<BakePlan> plan = PlanLight(
      PlanInput{index, scene.name, scene.source_path, spec, bake, name}, PlanCasters::kReachable);
  if (!plan.ok()) return plan;
  // Its sub-pixel rays are scanned around the receivers (core/bake/scan_windows.h).
  AddLightSpaceReceivers(scene, &*plan);
  plan->refinement = factor;
  plan->refined = std::move(refined);
  for (int t = 0; t < plan->tile_count(); ++t) {
    if (plan->tile_has_casters[t] && !plan->refined->LevelHasRays(plan->tile(t))) {
      plan->tile_has_casters[t] = false;
    }
  }
  if (bake.tile_group_size == 0) plan->group_side = LevelGroupSide(*plan);
  return plan;
}

namespace {

// The meshes of `scene` that `keep`, in light space of `frame`, in scene order.
template <typename Keep>
LightSpaceMesh LightSpaceMeshOf(const Scene& scene, const LightFrame& frame, Keep keep) {
  LightSpaceMesh out;
  size_t vertices = 0, indices = 0;
  for (const TriangleMesh& mesh : scene.meshes) {
    if (!keep(mesh)) continue;
    vertices += mesh.positions_world.size();
    indices += mesh.indices.size();
  }
  // Sized first: grown by push_back, a world's 10^6 triangles were copied and page-faulted
  // again at each doubling (perf, 2026-12-06).
  out.positions.reserve(vertices);
  out.indices.reserve(indices);
  for (const TriangleMesh& mesh : scene.meshes) {
    if (!keep(mesh)) continue;
    const uint32_t base = static_cast<uint32_t>(out.positions.size());
    for (const glm::dvec3& p : mesh.positions_world) {
      out.positions.push_back(glm::vec3(frame.LightFromWorld(p)));
    }
    for (uint32_t i : mesh.indices) out.indices.push_back(base + i);
  }
  return out;
}

}  // namespace

void AddLightSpaceReceivers(const Scene& scene, BakePlan* plan) {
  const LightFrame& frame = plan->geometry().frame;
  plan->receivers =
      LightSpaceMeshOf(scene, frame, [](const TriangleMesh& m) { return Receives(m.role); });
  plan->some_receivers_unrefined =
      plan->header.max_refinement > 1 &&
      std::any_of(scene.meshes.begin(), scene.meshes.end(),
                  [](const TriangleMesh& m) { return Receives(m.role) && !m.refine; });
  plan->refinable_receivers =
      plan->some_receivers_unrefined
          ? LightSpaceMeshOf(scene, frame,
                             [](const TriangleMesh& m) { return Receives(m.role) && m.refine; })
          : LightSpaceMesh{};
}

int64_t TileCountOf(const BakeSettings& bake) {
  const int64_t tile = std::max(1, bake.tile_size);
  return ((bake.width + tile - 1) / tile) * ((bake.height + tile - 1) / tile);
}

TileRect BakePlan::tile(int index) const {
  const int size = header.tile_size;
  TileRect rect;
  rect.index = index;
  rect.x0 = (index % tiles_x) * size;
  rect.y0 = (index / tiles_x) * size;
  rect.width = std::min(size, header.geometry.width - rect.x0);
  rect.height = std::min(size, header.geometry.height - rect.y0);
  return rect;
}

TileGroup BakePlan::group(int index) const {
  const int tx0 = (index % groups_x()) * group_side, ty0 = (index / groups_x()) * group_side;
  const int tx1 = std::min(tiles_x, tx0 + group_side), ty1 = std::min(tiles_y, ty0 + group_side);
  TileGroup group;
  group.index = index;
  group.tiles.reserve(static_cast<size_t>(tx1 - tx0) * static_cast<size_t>(ty1 - ty0));
  for (int ty = ty0; ty < ty1; ++ty) {
    for (int tx = tx0; tx < tx1; ++tx) group.tiles.push_back(ty * tiles_x + tx);
  }
  const TileRect first = tile(group.tiles.front()), last = tile(group.tiles.back());
  group.x0 = first.x0;
  group.y0 = first.y0;
  group.width = last.x0 + last.width - first.x0;
  group.height = last.y0 + last.height - first.y0;
  return group;
}

void ReleaseRenderGeometry(BakePlan* plan) {
  plan->casters = LightSpaceMesh{};
  plan->caster_clusters = std::vector<CasterCluster>{};
  plan->masks = {};
  // A surfaces-only plan, a refined one and a refinement level place their depth windows, and
  // choose their refined pixels, from the receivers.
  if (!plan->header.surfaces_only && plan->header.max_refinement <= 1 && plan->refinement <= 1) {
    plan->receivers = LightSpaceMesh{};
    plan->refinable_receivers = LightSpaceMesh{};
  } else {
    // Kept for as long as the job runs: without the slack their growth left.
    plan->receivers.positions.shrink_to_fit();
    plan->receivers.indices.shrink_to_fit();
  }
}

}  // namespace pdsm
