// The bake parameters of a scene message (after any overrides), validated into BakeSettings
// with every default filled in. Internal to core/scene (not a public API); see scene_loader.h
// for that.
#ifndef PDSM_CORE_SCENE_SCENE_BAKE_H_
#define PDSM_CORE_SCENE_SCENE_BAKE_H_

#include <set>
#include <string>

#include "absl/status/statusor.h"
#include "core/scene/field_checker.h"
#include "core/scene/scene.h"
#include "pdsm/v1/scene.pb.h"

namespace pdsm::internal {

// The settings `bake` asks for, unset fields at their defaults (scene.h). `shape` is the
// scene's light: a sun's orthographic frustum may start behind its plane. An adaptive bake
// (adaptiveTolerance > 0) refuses STRATIFIED sampling (SOBOL is every bake's default) and has its
// minimum sample count capped at `samples`. Errors (from `checks`, fields under "bake."): a count
// or size out of its [1, max] range (scene.h's kMax*), a value outside its interval, an unknown
// enum value, a malformed frustum.
absl::StatusOr<BakeSettings> BuildBake(const FieldChecker& checks, const pdsm::v1::BakeParams& bake,
                                       LightShape shape);

// `settings` as a message with every field set (depthBias only when the settings hold one):
// BuildBake of the result gives `settings` back, whatever the defaults.
pdsm::v1::BakeParams BakeParamsOf(const BakeSettings& settings);

// `top` laid over `base`: every field set in `top` (a present optional or message, a non-empty
// repeated field as a whole, a non-default enum) replaces base's; the others stay base's.
// When `replaced` is given it receives the JSON names of top's set fields ("samples").
pdsm::v1::BakeParams MergedBakeParams(const pdsm::v1::BakeParams& base,
                                      const pdsm::v1::BakeParams& top,
                                      std::set<std::string>* replaced = nullptr);

// Clears in `params` every field named (JSON names) in `names`.
void ClearBakeFields(const std::set<std::string>& names, pdsm::v1::BakeParams* params);

}  // namespace pdsm::internal

#endif  // PDSM_CORE_SCENE_SCENE_BAKE_H_
