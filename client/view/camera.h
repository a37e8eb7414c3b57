// The viewer's camera: a world-space eye, target and vertical field of view, turned into a
// light-space clip matrix in double (the GPU draws in light space, view_scene.h). The
// window's orbit controls move the eye on a sphere around the target.
#ifndef PDSM_CLIENT_VIEW_CAMERA_H_
#define PDSM_CLIENT_VIEW_CAMERA_H_

#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "absl/status/statusor.h"
#include "client/view/view_scene.h"

namespace pdsm::view {

struct Camera {
  glm::dvec3 eye_world{0, 5, 10};
  glm::dvec3 target_world{0.0};
  double fov_y_degrees = 45;
};

// What the default camera frames: the casters' bounds and the shadows they throw on the
// receivers (receiver points where the PDSM says A >= 0.02, sampled area-weighted). Only the
// casters while no PDSM pixel is baked yet; the whole scene when nothing casts.
void DefaultFraming(const ViewScene& scene, glm::dvec3* min_world, glm::dvec3* max_world);

// Looks down at DefaultFraming's box from above, turned about 60 degrees in azimuth away from
// the light's side so that shadows fall beside their casters, as close as holds the whole box
// in an image of `aspect` (width / height) with a 10% margin.
Camera DefaultCamera(const ViewScene& scene, double aspect = 16.0 / 9.0);

// The comma-separated finite numbers of a flag's value; INVALID_ARGUMENT naming `flag` and the
// first part that is not one. Shared by --camera and the dynamic-object flags.
absl::StatusOr<std::vector<double>> ParseFlagNumbers(const std::string& text,
                                                     const std::string& flag);

// "EX,EY,EZ,TX,TY,TZ[,FOV_DEG]" (world). INVALID_ARGUMENT naming `flag`.
absl::StatusOr<Camera> ParseCamera(const std::string& text, const std::string& flag);
std::string FormatCamera(const Camera& camera);

// World "up" used by the view and the orbit: +Y, unless the view looks along it.
glm::dvec3 CameraUp(const Camera& camera);

// clip_from_light for the given aspect (width / height); near and far planes hold the scene
// and its dynamic objects.
glm::mat4 ClipFromLight(const Camera& camera, const ViewScene& scene, double aspect);

// Orbit about the target: yaw about world up, pitch toward it (radians); zoom scales the
// distance.
void Orbit(Camera* camera, double yaw, double pitch);
void Zoom(Camera* camera, double factor);

}  // namespace pdsm::view

#endif  // PDSM_CLIENT_VIEW_CAMERA_H_
