// The light of a scene message, validated into a LightSpec. Internal to core/scene (not a
// public API); see scene_loader.h for that.
#ifndef PDSM_CORE_SCENE_SCENE_LIGHT_H_
#define PDSM_CORE_SCENE_SCENE_LIGHT_H_

#include "absl/status/statusor.h"
#include "core/scene/field_checker.h"
#include "core/scene/scene.h"
#include "pdsm/v1/scene.pb.h"

namespace pdsm::internal {

// The rect, disk or sun light of `light` with its frame. Errors (from `checks`, fields under
// "light."): no shape set, a non-finite or wrong-sized vector, a zero direction, a rect whose
// up is parallel to its normal, a size or radius not > 0, a sun diameter outside (0, 90) deg.
absl::StatusOr<LightSpec> BuildLight(const FieldChecker& checks, const pdsm::v1::Light& light);

}  // namespace pdsm::internal

#endif  // PDSM_CORE_SCENE_SCENE_LIGHT_H_
