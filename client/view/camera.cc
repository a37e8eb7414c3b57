#include "client/view/camera.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_split.h"
#include "core/pdsm/pdsm_query.h"

namespace pdsm::view {
namespace {

double SceneRadius(const ViewScene& scene) {
  return std::max(0.5 * glm::length(scene.bounds_max_world - scene.bounds_min_world), 1e-3);
}

}  // namespace

void DefaultFraming(const ViewScene& scene, glm::dvec3* min_world, glm::dvec3* max_world) {
  glm::dvec3 lo = scene.casters_min_world, hi = scene.casters_max_world;
  if (scene.pdsm) {
    // Receiver points, area-weighted: a fixed count spread over the triangles by error
    // diffusion (small triangles may get none), placed by the R2 sequence (Roberts 2018).
    constexpr int kPoints = 16384;
    constexpr double kShadow = 0.02;
    const double g = 1.32471795724474602596;  // the plastic number
    const double a1 = 1.0 / g, a2 = 1.0 / (g * g);
    double total = 0;
    for (const TriangleMesh& mesh : scene.scene.meshes) {
      if (!Receives(mesh.role)) continue;
      for (size_t i = 0; i + 2 < mesh.indices.size(); i += 3) {
        const glm::dvec3& p0 = mesh.positions_world[mesh.indices[i]];
        total += 0.5 * glm::length(glm::cross(mesh.positions_world[mesh.indices[i + 1]] - p0,
                                              mesh.positions_world[mesh.indices[i + 2]] - p0));
      }
    }
    double carry = 0;
    int64_t k = 0;
    std::vector<glm::dvec3> points;
    points.reserve(kPoints);
    for (const TriangleMesh& mesh : scene.scene.meshes) {
      if (!Receives(mesh.role) || !(total > 0)) continue;
      for (size_t i = 0; i + 2 < mesh.indices.size(); i += 3) {
        const glm::dvec3& p0 = mesh.positions_world[mesh.indices[i]];
        const glm::dvec3 e1 = mesh.positions_world[mesh.indices[i + 1]] - p0;
        const glm::dvec3 e2 = mesh.positions_world[mesh.indices[i + 2]] - p0;
        carry += kPoints * 0.5 * glm::length(glm::cross(e1, e2)) / total;
        for (; carry >= 1.0; carry -= 1.0, ++k) {
          double u = std::fmod(0.5 + a1 * k, 1.0), v = std::fmod(0.5 + a2 * k, 1.0);
          if (u + v > 1) u = 1 - u, v = 1 - v;
          points.push_back(p0 + u * e1 + v * e2);
        }
      }
    }
    // A tile that cannot be read frames nothing here; the frame reports the error.
    const absl::StatusOr<std::vector<std::optional<double>>> a = scene.pdsm->AttenuationAt(points);
    for (size_t i = 0; a.ok() && i < points.size(); ++i) {
      if ((*a)[i].has_value() && *(*a)[i] >= kShadow) {  // false for NaN
        lo = glm::min(lo, points[i]);
        hi = glm::max(hi, points[i]);
      }
    }
  }
  *min_world = lo;
  *max_world = hi;
}

Camera DefaultCamera(const ViewScene& scene, double aspect) {
  const LightFrame& f = scene.frame();
  Camera camera;
  glm::dvec3 lo, hi;
  DefaultFraming(scene, &lo, &hi);
  camera.target_world = 0.5 * (lo + hi);
  // From above, turned about 60 degrees in azimuth away from the light's side: shadows fall
  // beside their casters in view instead of hiding behind them.
  const glm::dvec3 up(0, 1, 0);
  glm::dvec3 toward_light = -f.n - up * glm::dot(-f.n, up);
  if (glm::length(toward_light) < 0.2) toward_light = f.u - up * glm::dot(f.u, up);
  if (glm::length(toward_light) < 1e-6) toward_light = glm::dvec3(1, 0, 0);
  toward_light = glm::normalize(toward_light);
  const glm::dvec3 side = glm::cross(up, toward_light);
  const glm::dvec3 back = glm::normalize(0.9 * up + 0.7 * side + 0.35 * toward_light);
  // As close as holds every corner of the box: a corner at (x, y) across and z toward the eye
  // from the target needs a distance D with |x| <= tan_h (D - z) and |y| <= tan_v (D - z).
  const glm::dvec3 forward = -back;
  const glm::dvec3 right = glm::normalize(glm::cross(forward, up));
  const glm::dvec3 view_up = glm::cross(right, forward);
  const double tan_v = std::tan(0.5 * glm::radians(camera.fov_y_degrees));
  const double tan_h = tan_v * std::max(aspect, 1e-3);
  constexpr double kMargin = 1.1;
  double distance = 1e-3 + 0.5 * glm::length(hi - lo);  // never inside the box
  for (int corner = 0; corner < 8; ++corner) {
    const glm::dvec3 c((corner & 1) ? hi.x : lo.x, (corner & 2) ? hi.y : lo.y,
                       (corner & 4) ? hi.z : lo.z);
    const glm::dvec3 r = c - camera.target_world;
    const double z = glm::dot(r, back);
    distance = std::max({distance, z + kMargin * std::abs(glm::dot(r, right)) / tan_h,
                         z + kMargin * std::abs(glm::dot(r, view_up)) / tan_v});
  }
  camera.eye_world = camera.target_world + distance * back;
  return camera;
}

absl::StatusOr<std::vector<double>> ParseFlagNumbers(const std::string& text,
                                                     const std::string& flag) {
  std::vector<double> numbers;
  for (absl::string_view part : absl::StrSplit(text, ',')) {
    double value = 0;
    if (!absl::SimpleAtod(part, &value) || !std::isfinite(value)) {
      return absl::InvalidArgumentError(
          absl::StrCat(flag, ": \"", part, "\" is not a finite number"));
    }
    numbers.push_back(value);
  }
  return numbers;
}

absl::StatusOr<Camera> ParseCamera(const std::string& text, const std::string& flag) {
  absl::StatusOr<std::vector<double>> parsed = ParseFlagNumbers(text, flag);
  if (!parsed.ok()) return parsed.status();
  const std::vector<double>& numbers = *parsed;
  if (numbers.size() != 6 && numbers.size() != 7) {
    return absl::InvalidArgumentError(absl::StrCat(
        flag, ": expected EX,EY,EZ,TX,TY,TZ[,FOV_DEG], got ", numbers.size(), " numbers"));
  }
  Camera camera;
  camera.eye_world = {numbers[0], numbers[1], numbers[2]};
  camera.target_world = {numbers[3], numbers[4], numbers[5]};
  if (numbers.size() == 7) camera.fov_y_degrees = numbers[6];
  if (!(camera.fov_y_degrees > 1 && camera.fov_y_degrees < 170)) {
    return absl::InvalidArgumentError(absl::StrCat(flag, ": FOV_DEG must be in (1, 170)"));
  }
  if (glm::length(camera.eye_world - camera.target_world) <= 0) {
    return absl::InvalidArgumentError(absl::StrCat(flag, ": eye and target are the same point"));
  }
  return camera;
}

std::string FormatCamera(const Camera& c) {
  return absl::StrFormat("%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.4g", c.eye_world.x, c.eye_world.y,
                         c.eye_world.z, c.target_world.x, c.target_world.y, c.target_world.z,
                         c.fov_y_degrees);
}

glm::dvec3 CameraUp(const Camera& camera) {
  const glm::dvec3 forward = glm::normalize(camera.target_world - camera.eye_world);
  const glm::dvec3 y(0, 1, 0);
  return std::abs(glm::dot(forward, y)) > 0.999 ? glm::dvec3(0, 0, -1) : y;
}

glm::mat4 ClipFromLight(const Camera& camera, const ViewScene& scene, double aspect) {
  const LightFrame& f = scene.frame();
  const glm::dvec3 eye = f.LightFromWorld(camera.eye_world);
  const glm::dvec3 target = f.LightFromWorld(camera.target_world);
  const glm::dvec3 up_world = CameraUp(camera);
  const glm::dvec3 up(glm::dot(up_world, f.u), glm::dot(up_world, f.v), glm::dot(up_world, f.n));
  const glm::dmat4 view = glm::lookAt(eye, target, up);
  // Depth range: the bounding sphere of the scene, grown for dynamic objects moved around it.
  const glm::dvec3 centre_world = 0.5 * (scene.bounds_min_world + scene.bounds_max_world);
  const double radius = 2.0 * SceneRadius(scene);
  const double distance = glm::length(camera.eye_world - centre_world);
  const double z_far = distance + radius;
  const double z_near = std::max(distance - radius, z_far * 1e-4);
  const glm::dmat4 projection =
      glm::perspective(glm::radians(camera.fov_y_degrees), aspect, z_near, z_far);
  return glm::mat4(projection * view);
}

void Orbit(Camera* camera, double yaw, double pitch) {
  const glm::dvec3 up = CameraUp(*camera);
  glm::dvec3 offset = camera->eye_world - camera->target_world;
  const double distance = glm::length(offset);
  glm::dvec3 dir = offset / distance;
  // Yaw: rotate about up (Rodrigues).
  const auto rotate = [](const glm::dvec3& v, const glm::dvec3& axis, double angle) {
    return v * std::cos(angle) + glm::cross(axis, v) * std::sin(angle) +
           axis * glm::dot(axis, v) * (1 - std::cos(angle));
  };
  dir = rotate(dir, up, yaw);
  const glm::dvec3 right = glm::normalize(glm::cross(up, dir));
  const glm::dvec3 pitched = rotate(dir, right, -pitch);
  if (std::abs(glm::dot(pitched, up)) < 0.995) dir = pitched;  // never flip over the pole
  camera->eye_world = camera->target_world + distance * dir;
}

void Zoom(Camera* camera, double factor) {
  camera->eye_world = camera->target_world + factor * (camera->eye_world - camera->target_world);
}

}  // namespace pdsm::view
