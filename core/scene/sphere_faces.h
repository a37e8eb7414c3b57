// A sphere light (a bulb; glTF's point lights) baked as faces (issue #12 item 2). A PDSM is a
// perspective map about one axis, so a light that shines every way is cut into the six faces of
// a cube about its centre: face k covers the directions nearer its axis than any other axis
// (|s|, |t| <= 1 about it), and samples the disk of the sphere's radius that faces that axis.
//
// The approximation, stated: from a point straight along a face's axis the sphere looks like
// that disk (exactly so for a distant point); from a point off the axis by an angle theta the
// disk looks like an ellipse, narrowed by cos(theta) along the direction of the offset, while
// the sphere still looks round. Penumbrae seen from there are narrower than the sphere's by that
// factor, up to 1 - cos(54.7 deg) = 42 % at a cube's corner directions and 29 % at its edges.
// So the bake turns each tile group's samples to face the group's own direction
// (core/bake/face_samples.h), which leaves only the angle within a group. docs/scene_format.md
// ("Sphere lights") gives both errors, measured against the Embree reference that samples the
// true sphere, and why the cube was kept.
//
// Each face is a light of the scene like any other (SceneLight; a PDSM file part; a task of the
// service), a disk whose LightSpec::face_tangent bounds its window; its name is the sphere's and
// the face's label joined by '@' ("lamp@+x"), a character light names may not hold, so face
// names never collide with other lights' and stay safe in file names. Readers put the faces of
// one sphere back together (core/pdsm/pdsm_lights.h).
#ifndef PDSM_CORE_SCENE_SPHERE_FACES_H_
#define PDSM_CORE_SCENE_SPHERE_FACES_H_

#include <array>
#include <string>
#include <string_view>

#include <glm/glm.hpp>

#include "core/scene/scene.h"

namespace pdsm {

struct SphereFace {
  const char* label;  // "+x", "-x", "+y", "-y", "+z", "-z"
  glm::dvec3 axis;    // the face's n, world axes
  glm::dvec3 u;       // the face's u; v = axis x u
};

inline constexpr int kSphereFaceCount = 6;
// The faces' window: a cube face holds the directions with |s|, |t| <= 1 about its axis.
inline constexpr double kSphereFaceTangent = 1.0;
// The name of a sphere light given none (a one-light scene's `light`): its faces' names need one.
inline constexpr const char* kDefaultSphereName = "sphere";
// Joins a sphere light's name and a face label in the faces' names.
inline constexpr char kSphereFaceSeparator = '@';

// The faces, in the order they are baked and stored.
const std::array<SphereFace, kSphereFaceCount>& SphereFaces();

// "lamp@+x": face `face` of the sphere light named `sphere` ("" gives kDefaultSphereName's).
std::string SphereFaceName(std::string_view sphere, const SphereFace& face);

// The sphere light whose face a light (or PDSM part) named `name` is: "lamp" for "lamp@+x"; ""
// for a name that is not a face's.
std::string_view SphereOfFace(std::string_view name);

// Face `face` of a sphere light of `radius` (world units, > 0) centred at `center` (world): a
// disk facing the face's axis, its window bounded by kSphereFaceTangent.
LightSpec SphereFaceLight(const glm::dvec3& center, double radius, const SphereFace& face);

}  // namespace pdsm

#endif  // PDSM_CORE_SCENE_SPHERE_FACES_H_
