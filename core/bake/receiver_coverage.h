// How much of the receivers a PDSM covers. A receiver outside the light's frustum -- behind a
// planar light, or beyond the window, which a perspective PDSM clamps at kMaxWindowTangent
// (85 degrees off the light's axis) -- gets no shadow from the bake: `pdsm query` answers nan
// there and the viewer draws it unshadowed. A disk light 3 above a 100 x 100 floor leaves 53%
// of the floor outside; `pdsm bake` says so instead of baking silently.
#ifndef PDSM_CORE_BAKE_RECEIVER_COVERAGE_H_
#define PDSM_CORE_BAKE_RECEIVER_COVERAGE_H_

#include "core/pdsm/pdsm_geometry.h"
#include "core/scene/scene.h"

namespace pdsm {

// The fraction (0..1) of the receiving meshes' total area that lies outside `geometry`'s
// frustum (PdsmGeometry::Locate refuses it): each triangle is clipped exactly against the
// frustum's planes in light space. 0 when the scene has no receiver area.
double ReceiverAreaOutsideFrustum(const Scene& scene, const PdsmGeometry& geometry);

}  // namespace pdsm

#endif  // PDSM_CORE_BAKE_RECEIVER_COVERAGE_H_
