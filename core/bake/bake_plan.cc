#include "core/bake/bake_plan.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "absl/strings/str_format.h"
#include "core/sampling/light_samples.h"

namespace pdsm {
namespace {

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

void FitTriangle(const glm::dvec3 tri[3], bool casts, Projection projection, double z_min,
                 WindowFit* fit) {
  glm::dvec3 clipped[4];
  const int n = projection == Projection::kPerspective ? ClipTriangleNear(tri, z_min, clipped)
                                                      : 3;
  if (projection == Projection::kOrthographic) std::copy(tri, tri + 3, clipped);
  for (int k = 0; k < n; ++k) {
    const glm::dvec3& p = clipped[k];
    double s = p.x, t = p.y;
    if (projection == Projection::kPerspective) {
      s = std::clamp(p.x / p.z, -kMaxWindowTangent, kMaxWindowTangent);
      t = std::clamp(p.y / p.z, -kMaxWindowTangent, kMaxWindowTangent);
    }
    fit->s_lo = std::min(fit->s_lo, s);
    fit->s_hi = std::max(fit->s_hi, s);
    fit->t_lo = std::min(fit->t_lo, t);
    fit->t_hi = std::max(fit->t_hi, t);
    if (casts) fit->z_near_casters = std::min(fit->z_near_casters, p.z);
    fit->z_far_all = std::max(fit->z_far_all, p.z);
  }
}

// Sun: the frame's centre is placed so that the whole scene lies at z in (0, 2R].
LightFrame SunFrame(const Scene& scene) {
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

void MakeTiles(BakePlan* plan) {
  const PdsmGeometry& g = plan->header.geometry;
  const int size = plan->header.tile_size;
  plan->tiles_x = (g.width + size - 1) / size;
  plan->tiles_y = (g.height + size - 1) / size;
  for (int ty = 0; ty < plan->tiles_y; ++ty) {
    for (int tx = 0; tx < plan->tiles_x; ++tx) {
      TileRect tile;
      tile.index = static_cast<int>(plan->tiles.size());
      tile.x0 = tx * size;
      tile.y0 = ty * size;
      tile.width = std::min(size, g.width - tile.x0);
      tile.height = std::min(size, g.height - tile.y0);
      plan->tiles.push_back(tile);
    }
  }
}

void FillHeader(const Scene& scene, BakePlan* plan) {
  PdsmHeader& h = plan->header;
  h.scene_name = scene.name;
  h.light_shape = scene.light.shape;
  h.light_half_width = scene.light.half_width;
  h.light_half_height = scene.light.half_height;
  h.light_radius = scene.light.radius;
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
}

}  // namespace

double DefaultDepthBias(double z_far) { return 1e-5 * std::abs(z_far); }

absl::StatusOr<BakePlan> PlanBake(const Scene& scene) {
  BakePlan plan;
  FillHeader(scene, &plan);
  PdsmGeometry& g = plan.header.geometry;
  g.projection = scene.light.shape == LightShape::kSun ? Projection::kOrthographic
                                                       : Projection::kPerspective;
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
  WindowFit fit;
  for (const TriangleMesh& mesh : scene.meshes) {
    for (size_t k = 0; k + 2 < mesh.indices.size(); k += 3) {
      const glm::dvec3 tri[3] = {g.frame.LightFromWorld(mesh.positions_world[mesh.indices[k]]),
                                 g.frame.LightFromWorld(mesh.positions_world[mesh.indices[k + 1]]),
                                 g.frame.LightFromWorld(mesh.positions_world[mesh.indices[k + 2]])};
      if (std::max({tri[0].z, tri[1].z, tri[2].z}) < z_min_fit) continue;  // behind the light
      FitTriangle(tri, Casts(mesh.role), g.projection, z_min_fit, &fit);
    }
  }

  if (scene.bake.frustum) {
    const FrustumOverride& f = *scene.bake.frustum;
    g.s_min = f.s_min;
    g.s_max = f.s_max;
    g.t_min = f.t_min;
    g.t_max = f.t_max;
    g.z_near = f.z_near;
    g.z_far = f.z_far;
    if (g.projection == Projection::kPerspective && !(f.z_near > 0)) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "%s: bake.frustum.depthRange[0]: must be > 0 for a %s light (got %g)",
          scene.source_path, "rect or disk", f.z_near));
    }
  } else if (fit.empty()) {
    g.s_min = g.t_min = -1;
    g.s_max = g.t_max = 1;
    g.z_near = 1;
    g.z_far = 2;
  } else {
    // A margin of 1e-3 of the window keeps silhouettes on the border inside it.
    const double ms = 1e-3 * std::max(fit.s_hi - fit.s_lo, 1e-9);
    const double mt = 1e-3 * std::max(fit.t_hi - fit.t_lo, 1e-9);
    g.s_min = fit.s_lo - ms;
    g.s_max = fit.s_hi + ms;
    g.t_min = fit.t_lo - mt;
    g.t_max = fit.t_hi + mt;
    g.z_far = fit.z_far_all;
    g.z_near = std::isfinite(fit.z_near_casters) ? fit.z_near_casters : fit.z_far_all;
  }

  plan.header.depth_bias = scene.bake.depth_bias.value_or(DefaultDepthBias(g.z_far));
  // Nothing nearer than the nearest caster can shadow; clip a hair in front of it.
  plan.z_clip_near = g.projection == Projection::kPerspective
                         ? g.z_near * (1.0 - 1e-6)
                         : g.z_near - 1e-6 * std::max(std::abs(g.z_far - g.z_near), 1e-9);
  plan.z_clip_far = g.z_far + 1e-3 * std::max(g.z_far - g.z_near, 1e-9);

  const double texel_pitch = std::max(g.s_max - g.s_min, g.t_max - g.t_min) /
                             scene.bake.shadow_map_resolution;
  plan.lattice = ShadowMapLattice{g.s_min, g.t_min, texel_pitch, texel_pitch};
  plan.samples = GenerateLightSamples(scene.light, scene.bake.samples, scene.bake.sampling,
                                      scene.bake.seed);
  MakeTiles(&plan);
  for (const TriangleMesh& mesh : scene.meshes) {
    if (Casts(mesh.role)) AppendMesh(mesh, g.frame, &plan.casters);
    if (Receives(mesh.role)) AppendMesh(mesh, g.frame, &plan.receivers);
  }
  return plan;
}

}  // namespace pdsm
