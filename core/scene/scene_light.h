// The light of a scene message, validated into a LightSpec. Internal to core/scene (not a
// public API); see scene_loader.h for that.
#ifndef PDSM_CORE_SCENE_SCENE_LIGHT_H_
#define PDSM_CORE_SCENE_SCENE_LIGHT_H_

#include <vector>

#include "absl/status/statusor.h"
#include "core/scene/field_checker.h"
#include "core/scene/scene.h"
#include "pdsm/v1/scene.pb.h"

namespace pdsm::internal {

// The rect, disk, spot or sun light of `light` with its frame. Errors (from `checks`, fields under
// "light."): no shape set, a non-finite or wrong-sized vector, a zero direction, a rect whose
// up is parallel to its normal, a size or radius not > 0, a sun diameter outside (0, 90) deg.
// REQUIRES: `light` is not a sphere (BuildSphereFaces).
absl::StatusOr<LightSpec> BuildLight(const FieldChecker& checks, const pdsm::v1::Light& light);

// A sphere light's faces (core/scene/sphere_faces.h), in SphereFaces' order. Errors as
// BuildLight's, its fields "light.sphere.center" and "light.sphere.radius".
absl::StatusOr<std::vector<LightSpec>> BuildSphereFaces(const FieldChecker& checks,
                                                        const pdsm::v1::SphereLight& sphere);

}  // namespace pdsm::internal

#endif  // PDSM_CORE_SCENE_SCENE_LIGHT_H_
