// A sphere face's light samples, as each of its tile groups uses them (issue #12 item 2;
// core/scene/sphere_faces.h). A face samples the disk of the sphere's radius facing its axis,
// and from a point off that axis by theta the disk looks narrowed by cos(theta) where the sphere
// still looks round. So each tile group uses the disk that faces its own direction w (the
// centre of its rays) instead: plan.samples, laid on the disk perpendicular to w, then moved
// along w onto the light plane (the pipeline's samples lie in it), where they make an ellipse
// stretched by 1 / cos(theta). Seen along w, that ellipse is exactly the sphere's outline; what
// is left is the angle between a ray and its group's centre, which kMaxFaceGroupTangent keeps
// under about 7 degrees (a penumbra width off by under 1 %, against up to 42 % for the face's
// own disk at a cube's corner directions; measured in docs/scene_format.md, "Sphere lights").
// A pure function of the plan and the group: every process of a bake uses the same samples.
#ifndef PDSM_CORE_BAKE_FACE_SAMPLES_H_
#define PDSM_CORE_BAKE_FACE_SAMPLES_H_

#include <vector>

#include <glm/glm.hpp>

#include "core/bake/bake_plan.h"

namespace pdsm {

// The widest span of window tangent (s or t) one tile group of a sphere face covers.
inline constexpr double kMaxFaceGroupTangent = 0.25;

inline bool IsSphereFacePlan(const BakePlan& plan) { return plan.header.face_tangent > 0; }

// Group `group_index`'s samples: light-plane offsets (a, b), one per plan.samples entry, in
// order. REQUIRES: IsSphereFacePlan(plan); group_index < plan.group_count().
std::vector<glm::dvec2> FaceGroupSamples(const BakePlan& plan, int group_index);

// How far FaceGroupSamples' offsets reach at most, as a multiple of plan.samples' (1 / cos of
// the window's widest direction; 1 for any light but a sphere face): what the bounds on the
// samples' extent (tile reach, group windows, scan floor) multiply by.
double FaceSampleStretch(const BakePlan& plan);

}  // namespace pdsm

#endif  // PDSM_CORE_BAKE_FACE_SAMPLES_H_
