#include "core/bake/bake_plan.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "absl/strings/str_format.h"
#include "core/bake/caster_culling.h"
#include "core/bake/face_samples.h"
#include "core/bake/tile_reach.h"
#include "core/sampling/light_samples.h"

namespace pdsm {
namespace {

// What a plan reads of a scene: its meshes (referred to, never copied: a world's are tens of
// MB, and a job plans each of its lights), its names, and the one light it bakes with that
// light's settings. The members are named as Scene's.
struct PlanInput {
  const std::vector<TriangleMesh>& meshes;
  const std::string& name;
  const std::string& source_path;
  const LightSpec& light;
  const BakeSettings& bake;
  const std::string& light_name;
};

constexpr double kInf = std::numeric_limits<double>::infinity();

struct Bounds3 {
  glm::dvec3 lo{kInf}, hi{-kInf};
  void Add(const glm::dvec3& p) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  bool empty() const { return lo.x > hi.x; }
};

struct WindowFit {
  double s_lo = kInf, s_hi = -kInf, t_lo = kInf, t_hi = -kInf;
  double z_near_casters = kInf, z_far_all = -kInf;
  double z_near_receivers = kInf;
  // The nearest caster depth anywhere in front of the light, inside the window or not: where
  // the window is stretched by geometry near the light plane (the refit in PlanBake).
  double z_near_casters_anywhere = kInf;
  bool empty() const { return s_lo > s_hi; }
};

// The part of triangle (a, b, c) with z >= z_min (Sutherland–Hodgman against one plane).
int ClipTriangleNear(const glm::dvec3 tri[3], double z_min, glm::dvec3 out[4]) {
  int n = 0;
  for (int k = 0; k < 3; ++k) {
    const glm::dvec3& p = tri[k];
    const glm::dvec3& q = tri[(k + 1) % 3];
    const bool p_in = p.z >= z_min, q_in = q.z >= z_min;
    if (p_in) out[n++] = p;
    if (p_in != q_in) {
      const double f = (z_min - p.z) / (q.z - p.z);
      out[n++] = p + f * (q - p);
      out[n - 1].z = z_min;
    }
  }
  return n;
}

// The part of convex polygon `in` (n vertices) where `side(p)` <= 0, `side` affine
// (Sutherland–Hodgman against one plane). `out` holds n + 1 vertices.
template <typename Side>
int ClipPolygon(const glm::dvec3* in, int n, Side side, glm::dvec3* out) {
  int m = 0;
  for (int k = 0; k < n; ++k) {
    const glm::dvec3& p = in[k];
    const glm::dvec3& q = in[(k + 1) % n];
    const double fp = side(p), fq = side(q);
    if (fp <= 0) out[m++] = p;
    if ((fp <= 0) != (fq <= 0)) out[m++] = p + (fp / (fp - fq)) * (q - p);
  }
  return m;
}

// The nearest depth of polygon `poly` (n <= 4 vertices, z > 0) inside the pyramid |x| <=
// max_tangent z + reach_x, |y| <= max_tangent z + reach_y; +inf when none of it is inside.
// With reach 0 that is the window's own pyramid (what a receiver needs resolved); with the
// light's half extents it holds every point between a sample and a point in the window (what
// a caster can shadow there: x' = a + (x - a) z' / z).
double NearestDepthInPyramid(const glm::dvec3* poly, int n, double max_tangent, double reach_x,
                             double reach_y) {
  glm::dvec3 a[8], b[8];
  n = ClipPolygon(
      poly, n, [&](const glm::dvec3& p) { return p.x - max_tangent * p.z - reach_x; }, a);
  n = ClipPolygon(
      a, n, [&](const glm::dvec3& p) { return -p.x - max_tangent * p.z - reach_x; }, b);
  n = ClipPolygon(
      b, n, [&](const glm::dvec3& p) { return p.y - max_tangent * p.z - reach_y; }, a);
  n = ClipPolygon(
      a, n, [&](const glm::dvec3& p) { return -p.y - max_tangent * p.z - reach_y; }, b);
  double z = kInf;
  for (int k = 0; k < n; ++k) z = std::min(z, b[k].z);
  return z;
}

// How far from its centre a light's samples reach across its plane: the half extents along x
// and y (a sphere face's groups stretch its disk by up to 1 / cos of its widest direction:
// core/bake/face_samples.h).
glm::dvec2 LightReach(const LightSpec& light) {
  const double t = light.face_tangent;
  switch (light.shape) {
    case LightShape::kRect:
      return {light.half_width, light.half_height};
    case LightShape::kDisk:
      return glm::dvec2(light.radius * std::sqrt(1 + 2 * t * t));
    case LightShape::kSun:
      break;
  }
  return {0, 0};
}

// `max_tangent`: perspective windows stop at |s|, |t| <= it (kMaxWindowTangent, a spot's cone
// or a sphere's face); `reach`: LightReach. A perspective triangle's s, t outside the window
// count at its edge, while its depths count only where it lies inside the window's pyramid
// (receivers) or can shadow a point in it (casters): a ground that crosses a sideways light's
// plane far below the light once made the nearest caster 1e-5 away (bench/sphere_faces.py).
void FitTriangle(const glm::dvec3 tri[3], bool casts, bool receives, Projection projection,
                 double z_min, double max_tangent, const glm::dvec2& reach, WindowFit* fit) {
  glm::dvec3 clipped[4];
  const int n = projection == Projection::kPerspective ? ClipTriangleNear(tri, z_min, clipped) : 3;
  if (projection == Projection::kOrthographic) std::copy(tri, tri + 3, clipped);
  for (int k = 0; k < n; ++k) {
    const glm::dvec3& p = clipped[k];
    double s = p.x, t = p.y;
    if (projection == Projection::kPerspective) {
      s = std::clamp(p.x / p.z, -max_tangent, max_tangent);
      t = std::clamp(p.y / p.z, -max_tangent, max_tangent);
    }
    fit->s_lo = std::min(fit->s_lo, s);
    fit->s_hi = std::max(fit->s_hi, s);
    fit->t_lo = std::min(fit->t_lo, t);
    fit->t_hi = std::max(fit->t_hi, t);
    if (casts) fit->z_near_casters_anywhere = std::min(fit->z_near_casters_anywhere, p.z);
    if (projection == Projection::kOrthographic) {
      if (casts) fit->z_near_casters = std::min(fit->z_near_casters, p.z);
      if (receives) fit->z_near_receivers = std::min(fit->z_near_receivers, p.z);
    }
    fit->z_far_all = std::max(fit->z_far_all, p.z);
  }
  if (projection == Projection::kPerspective && n > 0) {
    if (casts) {
      fit->z_near_casters = std::min(
          fit->z_near_casters, NearestDepthInPyramid(clipped, n, max_tangent, reach.x, reach.y));
    }
    if (receives) {
      fit->z_near_receivers =
          std::min(fit->z_near_receivers, NearestDepthInPyramid(clipped, n, max_tangent, 0, 0));
    }
  }
}

// Sun: the frame's centre is placed so that the whole scene lies at z in (0, 2R].
LightFrame SunFrame(const PlanInput& scene) {
  Bounds3 bounds;
  for (const TriangleMesh& mesh : scene.meshes) {
    for (const glm::dvec3& p : mesh.positions_world) bounds.Add(p);
  }
  LightFrame frame = scene.light.frame;
  if (bounds.empty()) {
    frame.center = -frame.n;
    return frame;
  }
  const glm::dvec3 mid = 0.5 * (bounds.lo + bounds.hi);
  const double radius = std::max(0.5 * glm::length(bounds.hi - bounds.lo), 1e-9);
  frame.center = mid - (radius * 1.01) * frame.n;
  return frame;
}

void AppendMesh(const TriangleMesh& mesh, const LightFrame& frame, LightSpaceMesh* out) {
  const uint32_t base = static_cast<uint32_t>(out->positions.size());
  for (const glm::dvec3& p : mesh.positions_world) {
    out->positions.push_back(glm::vec3(frame.LightFromWorld(p)));
  }
  for (uint32_t i : mesh.indices) out->indices.push_back(base + i);
}

// The casters' masks, UVs and per-triangle mask indices (after AppendMesh has added every
// caster mesh, in the same order); nothing when every caster is opaque. Equal masks of
// different meshes (one file referenced twice) become one.
absl::Status AppendCasterMasks(const PlanInput& scene, BakePlan* plan) {
  bool any = false;
  for (const TriangleMesh& mesh : scene.meshes) any = any || (Casts(mesh.role) && mesh.has_masks());
  if (!any) return absl::OkStatus();
  LightSpaceMesh& casters = plan->casters;
  casters.uvs.reserve(casters.positions.size());
  casters.triangle_masks.reserve(casters.TriangleCount());
  for (const TriangleMesh& mesh : scene.meshes) {
    if (!Casts(mesh.role)) continue;
    const size_t triangles = mesh.indices.size() / 3;
    if (!mesh.has_masks()) {
      casters.uvs.insert(casters.uvs.end(), mesh.positions_world.size(), glm::vec2(0.0f));
      casters.triangle_masks.insert(casters.triangle_masks.end(), triangles, 0);
      continue;
    }
    std::vector<uint16_t> plan_index(mesh.masks.size() + 1, 0);
    for (size_t k = 0; k < mesh.masks.size(); ++k) {
      size_t index = std::find_if(plan->masks.begin(), plan->masks.end(),
                                  [&](const auto& m) {
                                    return m == mesh.masks[k] || SameMask(*m, *mesh.masks[k]);
                                  }) -
                     plan->masks.begin();
      if (index == plan->masks.size()) {
        if (index == UINT16_MAX) {
          return absl::InvalidArgumentError(
              absl::StrFormat("%s: more than %d alpha-tested textures in the scene",
                              scene.source_path, UINT16_MAX));
        }
        plan->masks.push_back(mesh.masks[k]);
      }
      plan_index[k + 1] = static_cast<uint16_t>(index + 1);
    }
    casters.uvs.insert(casters.uvs.end(), mesh.uvs.begin(), mesh.uvs.end());
    for (const uint16_t k : mesh.triangle_masks) casters.triangle_masks.push_back(plan_index[k]);
  }
  return absl::OkStatus();
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
  h.slope_bias = scene.bake.slope_bias;
  h.sampling = scene.bake.sampling;
  h.seed = scene.bake.seed;
  if (scene.bake.adaptive()) {
    h.adaptive_tolerance = scene.bake.adaptive_tolerance;
    h.adaptive_min_samples = scene.bake.adaptive_min_samples;
  }
  h.tile_size = scene.bake.tile_size;
  h.surfaces_only = scene.bake.surfaces_only;
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

// The bounds of the scene's triangles (only receivers when asked) beyond z_min, projected.
WindowFit FitScene(const PlanInput& scene, const PdsmGeometry& g, double z_min,
                   bool receivers_only) {
  WindowFit fit;
  const double max_tangent = MaxWindowTangent(scene.light);
  const glm::dvec2 reach = LightReach(scene.light);
  for (const TriangleMesh& mesh : scene.meshes) {
    if (receivers_only && !Receives(mesh.role)) continue;
    for (size_t k = 0; k + 2 < mesh.indices.size(); k += 3) {
      const glm::dvec3 tri[3] = {g.frame.LightFromWorld(mesh.positions_world[mesh.indices[k]]),
                                 g.frame.LightFromWorld(mesh.positions_world[mesh.indices[k + 1]]),
                                 g.frame.LightFromWorld(mesh.positions_world[mesh.indices[k + 2]])};
      if (std::max({tri[0].z, tri[1].z, tri[2].z}) < z_min) continue;  // behind the light
      FitTriangle(tri, Casts(mesh.role), Receives(mesh.role), g.projection, z_min, max_tangent,
                  reach, &fit);
    }
  }
  return fit;
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
  Bounds3 world_bounds;
  for (const TriangleMesh& mesh : scene.meshes) {
    for (const glm::dvec3& p : mesh.positions_world) world_bounds.Add(p);
  }
  const double scene_size =
      world_bounds.empty() ? 1.0 : std::max(glm::length(world_bounds.hi - world_bounds.lo), 1e-30);
  const double z_min_fit = 1e-6 * scene_size;
  const WindowFit fit = FitScene(scene, g, z_min_fit, /*receivers_only=*/false);

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
    const WindowFit refit = FitScene(scene, g, plan.z_scan_floor, /*receivers_only=*/true);
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
  // Sized first: grown by push_back, a world's 10^6 triangles were copied and page-faulted
  // again at each doubling, a third of a coordinator's planning time (perf, 2026-12-06).
  size_t caster_vertices = 0, caster_indices = 0, receiver_vertices = 0, receiver_indices = 0;
  for (const TriangleMesh& mesh : scene.meshes) {
    if (Casts(mesh.role)) {
      caster_vertices += mesh.positions_world.size();
      caster_indices += mesh.indices.size();
    }
    if (Receives(mesh.role)) {
      receiver_vertices += mesh.positions_world.size();
      receiver_indices += mesh.indices.size();
    }
  }
  plan.casters.positions.reserve(caster_vertices);
  plan.casters.indices.reserve(caster_indices);
  plan.receivers.positions.reserve(receiver_vertices);
  plan.receivers.indices.reserve(receiver_indices);
  for (const TriangleMesh& mesh : scene.meshes) {
    if (Casts(mesh.role)) AppendMesh(mesh, g.frame, &plan.casters);
    if (Receives(mesh.role)) AppendMesh(mesh, g.frame, &plan.receivers);
  }
  if (absl::Status s = AppendCasterMasks(scene, &plan); !s.ok()) return s;
  plan.caster_clusters = ClusterCasters(&plan.casters);
  plan.tile_group_size = scene.bake.tile_group_size;
  plan.group_side = GroupSideInTiles(plan);
  plan.tile_has_casters = TilesCastersMayReach(plan);
  // After the spatial sort, which spans what it is given (the kept triangles keep the order
  // they have among every caster: draw order settles depth ties), and after the tiles are
  // marked: a tile's task, even one whose reach only holds triangles that cannot shadow, widens
  // its group's shadow-map windows, and so moves the maps' projections (caster_culling.h).
  if (casters == PlanCasters::kReachable) {
    plan.casters_left_out = LeaveOutUnreachableCasters(&plan);
  }
  return plan;
}

}  // namespace

absl::StatusOr<BakePlan> PlanBake(const Scene& scene, PlanCasters casters) {
  return PlanLight(PlanInput{scene.meshes, scene.name, scene.source_path, scene.light, scene.bake,
                             scene.light_name},
                   casters);
}

absl::StatusOr<BakePlan> PlanBake(const Scene& scene, size_t light, PlanCasters casters) {
  const SceneLight one = LightOf(scene, light);
  return PlanLight(
      PlanInput{scene.meshes, scene.name, scene.source_path, one.spec, one.bake, one.name},
      casters);
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
  if (!plan->header.surfaces_only) {
    plan->receivers = LightSpaceMesh{};
  } else {
    // Kept for as long as the job runs: without the slack their growth left.
    plan->receivers.positions.shrink_to_fit();
    plan->receivers.indices.shrink_to_fit();
  }
}

}  // namespace pdsm
