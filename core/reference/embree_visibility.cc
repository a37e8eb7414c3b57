#include "core/reference/embree_visibility.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <thread>

#include <embree3/rtcore.h>

#include "absl/strings/str_format.h"
#include "core/reference/embree_handles.h"
#include "core/sampling/hash_rng.h"
#include "core/sampling/light_samples.h"
#include "core/util/work_queue.h"

namespace pdsm {
namespace {

// Hits on a triangle whose plane passes within this distance (relative to the scene's size) of the
// point are the point's own surface: the exact method's margin (kNearPointMargin).
constexpr double kCoplanarMargin = 1e-9;
// Float roundings of a coordinate of magnitude `scale` (2^-24 relative each): the ray starts this
// many of them away from the point, past where rounding alone could put a hit.
constexpr double kRoundingsOffset = 16.0;
constexpr int kMaxReferenceSamples = 1 << 20;

// Casters in rebased light space, in double (for the filter) and float (for Embree).
struct Casters {
  std::vector<glm::dvec3> vertices;  // 3 per triangle
  // Alpha-tested casters (core/scene/alpha_mask.h): per triangle its mask (null: opaque) and
  // 3 UVs; both empty when every caster is opaque.
  std::vector<const AlphaMask*> masks;
  std::vector<glm::vec2> uvs;
  std::vector<std::shared_ptr<const AlphaMask>> held;  // keeps `masks` alive
  glm::dvec3 origin_light{0.0};                        // subtracted from light-space coordinates
  double scale = 1.0;                                  // largest rebased coordinate magnitude
};

// The ray context Embree hands to the filter: extended with the query point in double.
struct PointContext {
  RTCIntersectContext embree;  // first member: Embree passes a pointer to it
  glm::dvec3 point;
  double margin;
};

absl::StatusOr<Casters> GatherCasters(const Scene& scene) {
  Casters casters;
  const LightFrame& frame = scene.light.frame;
  glm::dvec3 lo(std::numeric_limits<double>::infinity()), hi(-lo);
  bool any_masks = false;
  for (const TriangleMesh& mesh : scene.meshes) any_masks |= Casts(mesh.role) && mesh.has_masks();
  for (const TriangleMesh& mesh : scene.meshes) {
    if (!Casts(mesh.role)) continue;
    if (any_masks) {
      const size_t triangles = mesh.indices.size() / 3;
      for (size_t t = 0; t < triangles; ++t) {
        const uint16_t k = mesh.has_masks() ? mesh.triangle_masks[t] : 0;
        casters.masks.push_back(k == 0 ? nullptr : mesh.masks[k - 1].get());
        for (int c = 0; c < 3; ++c) {
          casters.uvs.push_back(mesh.has_masks() ? mesh.uvs[mesh.indices[3 * t + c]]
                                                 : glm::vec2(0.0f));
        }
      }
      casters.held.insert(casters.held.end(), mesh.masks.begin(), mesh.masks.end());
    }
    for (uint32_t index : mesh.indices) {
      if (index >= mesh.positions_world.size()) {
        return absl::InvalidArgumentError(absl::StrFormat("%s: index %d out of range (%d vertices)",
                                                          mesh.label, index,
                                                          mesh.positions_world.size()));
      }
      const glm::dvec3 v = frame.LightFromWorld(mesh.positions_world[index]);
      lo = glm::min(lo, v);
      hi = glm::max(hi, v);
      casters.vertices.push_back(v);
    }
    casters.vertices.resize(casters.vertices.size() / 3 * 3);
  }
  // A sun's frame centre is arbitrary: rebase on the casters instead, so floats keep digits.
  if (scene.light.shape == LightShape::kSun && !casters.vertices.empty()) {
    casters.origin_light = 0.5 * (lo + hi);
  }
  for (glm::dvec3& v : casters.vertices) {
    v -= casters.origin_light;
    casters.scale = std::max({casters.scale, std::abs(v.x), std::abs(v.y), std::abs(v.z)});
  }
  return casters;
}

// Rejects hits on the query point's own surface (a plane through the point), in double, and
// hits where an alpha-tested caster's mask lets the light through.
void FilterHits(const RTCFilterFunctionNArguments* args) {
  const auto* context = reinterpret_cast<const PointContext*>(args->context);
  const auto* casters = static_cast<const Casters*>(args->geometryUserPtr);
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] == 0) continue;
    const unsigned prim = RTCHitN_primID(args->hit, args->N, i);
    if (!casters->masks.empty() && casters->masks[prim] != nullptr) {
      // Embree's barycentrics: u weights the second vertex, v the third.
      const double u = RTCHitN_u(args->hit, args->N, i), v = RTCHitN_v(args->hit, args->N, i);
      const glm::dvec2 uv = (1 - u - v) * glm::dvec2(casters->uvs[3 * prim]) +
                            u * glm::dvec2(casters->uvs[3 * prim + 1]) +
                            v * glm::dvec2(casters->uvs[3 * prim + 2]);
      if (!casters->masks[prim]->CastsAt(uv)) {
        args->valid[i] = 0;
        continue;
      }
    }
    const glm::dvec3& a = casters->vertices[3 * prim];
    const glm::dvec3 normal =
        glm::cross(casters->vertices[3 * prim + 1] - a, casters->vertices[3 * prim + 2] - a);
    const double length = glm::length(normal);
    if (length == 0.0 ||
        std::abs(glm::dot(normal, context->point - a)) <= context->margin * length) {
      args->valid[i] = 0;
    }
  }
}

absl::StatusOr<RTCScene> BuildScene(RTCDevice device, const Casters& casters) {
  RTCScene rtc_scene = rtcNewScene(device);
  rtcSetSceneFlags(rtc_scene, RTC_SCENE_FLAG_ROBUST);
  rtcSetSceneBuildQuality(rtc_scene, RTC_BUILD_QUALITY_HIGH);
  const size_t triangles = casters.vertices.size() / 3;
  if (triangles > 0) {
    RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* vertices = static_cast<float*>(
        rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                3 * sizeof(float), casters.vertices.size()));
    auto* indices = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
        geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), triangles));
    if (vertices == nullptr || indices == nullptr) {
      rtcReleaseGeometry(geometry);
      rtcReleaseScene(rtc_scene);
      return absl::InternalError("embree: cannot allocate the caster buffers");
    }
    for (size_t k = 0; k < casters.vertices.size(); ++k) {
      for (int c = 0; c < 3; ++c) vertices[3 * k + c] = static_cast<float>(casters.vertices[k][c]);
      indices[k] = static_cast<unsigned>(k);
    }
    rtcSetGeometryUserData(geometry, const_cast<Casters*>(&casters));
    rtcSetGeometryOccludedFilterFunction(geometry, FilterHits);
    rtcCommitGeometry(geometry);
    rtcAttachGeometry(rtc_scene, geometry);
    rtcReleaseGeometry(geometry);
  }
  rtcCommitScene(rtc_scene);
  if (rtcGetDeviceError(device) != RTC_ERROR_NONE) {
    rtcReleaseScene(rtc_scene);
    return absl::InternalError("embree: building the caster scene failed");
  }
  return rtc_scene;
}

// The rays from p (rebased light space) to its light samples: each direction reaches its
// sample at t = 1 (rect, disk, sphere) or points to the sun (t unbounded).
struct SampleRays {
  std::vector<glm::dvec3> directions;
  bool unbounded = false;
};

// Rect/disk: to the sample on the light plane. Sun: towards the sun.
SampleRays PlanarOrSunRays(const Scene& scene, const Casters& casters, const glm::dvec3& p,
                           const std::vector<glm::dvec2>& samples) {
  SampleRays rays;
  rays.unbounded = scene.light.shape == LightShape::kSun;
  for (const glm::dvec2& s : samples) {
    rays.directions.push_back(rays.unbounded
                                  ? -glm::dvec3(s.x, s.y, 1.0)
                                  : glm::dvec3(s.x, s.y, 0.0) - casters.origin_light - p);
  }
  return rays;
}

// A sphere light (every face of one, core/scene/sphere_faces.h): the true sphere, not the face's
// disk. Directions uniform in the solid angle the sphere subtends from p (the cone of half-angle
// asin(r / d) towards its centre), each reaching the sphere's near side: a sphere hides as much
// of itself as the solid angle hidden, the definition the faces approximate. Empty for a point
// inside the sphere.
SampleRays SphereRays(const Scene& scene, const Casters& casters, const glm::dvec3& p,
                      const std::vector<glm::dvec2>& unit_square) {
  SampleRays rays;
  const glm::dvec3 to_center = -casters.origin_light - p;
  const double d = glm::length(to_center);
  const double r = scene.light.radius;
  if (!(d > r)) return rays;
  const glm::dvec3 w = to_center / d;
  const LightFrame basis = MakeLightFrame(glm::dvec3(0.0), w, nullptr);
  const double cos_max = std::sqrt(std::max(0.0, 1.0 - (r / d) * (r / d)));
  for (const glm::dvec2& u : unit_square) {
    const double cos_theta = 1.0 - u.x * (1.0 - cos_max);
    const double sin_theta = std::sqrt(std::max(0.0, 1.0 - cos_theta * cos_theta));
    const double phi = 2.0 * std::numbers::pi * u.y;
    const glm::dvec3 dir = sin_theta * std::cos(phi) * basis.u +
                           sin_theta * std::sin(phi) * basis.v + cos_theta * basis.n;
    // The near intersection with the sphere: d cos - sqrt(r^2 - d^2 sin^2).
    const double t =
        d * cos_theta - std::sqrt(std::max(0.0, r * r - d * d * sin_theta * sin_theta));
    rays.directions.push_back(t * dir);
  }
  return rays;
}

// The weight of the sample along `direction` (light_weighting.h): 1 unweighted; cos θ_light / r²
// for a planar light's emitter weighting (a sun's directions and a sphere's, drawn by solid
// angle, weigh 1); times max(0, cos θ_receiver) for irradiance. `normal` is in light space.
double SampleWeight(const WeightingSpec& weighting, const glm::dvec3& normal, bool planar,
                    const glm::dvec3& direction) {
  if (weighting.kind == LightWeighting::kUnweighted) return 1.0;
  const double r = glm::length(direction);
  // The planar light's normal is light space's z axis; `direction` reaches the sample at t = 1.
  double weight = planar ? std::abs(direction.z) / (r * r * r) : 1.0;
  if (weighting.kind == LightWeighting::kIrradiance) {
    weight *= std::max(0.0, glm::dot(normal, direction) / r);
  }
  return weight;
}

double HiddenFraction(RTCScene rtc_scene, const Casters& casters, const glm::dvec3& p,
                      const SampleRays& rays, const WeightingSpec& weighting,
                      const glm::dvec3& normal, bool planar) {
  const double scale = std::max(casters.scale, glm::length(p));
  const double offset = kRoundingsOffset * std::ldexp(scale, -24);
  PointContext context;
  rtcInitIntersectContext(&context.embree);
  context.point = p;
  context.margin = kCoplanarMargin * scale;
  double hidden = 0.0, whole = 0.0;
  for (const glm::dvec3& direction : rays.directions) {
    const double weight = SampleWeight(weighting, normal, planar, direction);
    whole += weight;
    if (weight == 0.0) continue;
    RTCRay ray;
    ray.org_x = static_cast<float>(p.x);
    ray.org_y = static_cast<float>(p.y);
    ray.org_z = static_cast<float>(p.z);
    ray.dir_x = static_cast<float>(direction.x);
    ray.dir_y = static_cast<float>(direction.y);
    ray.dir_z = static_cast<float>(direction.z);
    ray.tnear = static_cast<float>(offset / glm::length(direction));
    ray.tfar = rays.unbounded ? std::numeric_limits<float>::infinity() : 1.0f;
    ray.time = 0.0f;
    ray.mask = ~0u;
    ray.id = 0;
    ray.flags = 0;
    rtcOccluded1(rtc_scene, &context.embree, &ray);
    if (ray.tfar < 0.0f) hidden += weight;  // Embree marks an occluded ray with tfar = -inf
  }
  // Unweighted: a count over the count, as ever. Weighted: NaN where the receiver sees none of
  // the light (every weight 0).
  return whole > 0.0 ? hidden / whole : std::numeric_limits<double>::quiet_NaN();
}

}  // namespace

absl::StatusOr<std::vector<double>> EmbreeAttenuation(const Scene& scene,
                                                      std::span<const glm::dvec3> points_world,
                                                      int samples, uint64_t seed,
                                                      const WeightingSpec& weighting) {
  if (samples < 1 || samples > kMaxReferenceSamples) {
    return absl::InvalidArgumentError(
        absl::StrFormat("--samples: must be in [1, %d] (got %d)", kMaxReferenceSamples, samples));
  }
  absl::StatusOr<Casters> casters = GatherCasters(scene);
  if (!casters.ok()) return casters.status();
  EmbreeDevice device(rtcNewDevice(nullptr));
  if (device == nullptr) return absl::InternalError("embree: cannot create a device");
  absl::StatusOr<RTCScene> built = BuildScene(device.get(), *casters);
  if (!built.ok()) return built.status();
  EmbreeScene rtc_scene(*built);

  const bool sun = scene.light.shape == LightShape::kSun;
  const bool sphere = scene.light.is_sphere_face();
  const glm::dvec3 normal_light = weighting.NormalInLightSpace(scene.light.frame);
  std::vector<double> result(points_world.size(), std::numeric_limits<double>::quiet_NaN());
  std::atomic<size_t> next{0};  // points are independent: each writes only its own slot
  RunOnAllCores(points_world.size(), [&] {
    for (size_t i = next++; i < points_world.size(); i = next++) {
      const glm::dvec3 p_light = scene.light.frame.LightFromWorld(points_world[i]);
      if (!std::isfinite(p_light.x) || !std::isfinite(p_light.y) || !std::isfinite(p_light.z) ||
          (!sun && !sphere && !(p_light.z > 0.0))) {
        continue;  // stays NaN: behind the light, like `pdsm query` outside the
                   // frustum
      }
      const glm::dvec3 p = p_light - casters->origin_light;
      // Per point its own stratification: independent errors between points.
      const SampleRays rays =
          sphere ? SphereRays(scene, *casters, p, StratifiedUnitSquare(samples, HashInts(seed, i)))
                 : PlanarOrSunRays(
                       scene, *casters, p,
                       GenerateLightSamples(scene.light, samples, SamplingPattern::kStratified,
                                            HashInts(seed, i)));
      if (rays.directions.empty()) continue;  // inside a sphere light: NaN
      result[i] = HiddenFraction(rtc_scene.get(), *casters, p, rays, weighting, normal_light,
                                 /*planar=*/!sun && !sphere);
    }
  });
  return result;
}

}  // namespace pdsm
