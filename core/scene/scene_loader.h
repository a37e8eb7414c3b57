// Reads a scene file (the JSON mapping of pdsm.v1.Scene), loads its meshes, and validates
// everything into a Scene. Every error names the file and the field, e.g.
//   "examples/plates/scene.json: meshes[1].transform[3]: must be finite (got NaN)".
#ifndef PDSM_CORE_SCENE_SCENE_LOADER_H_
#define PDSM_CORE_SCENE_SCENE_LOADER_H_

#include <string>

#include "absl/status/statusor.h"
#include "core/scene/scene.h"
#include "pdsm/v1/scene.pb.h"

namespace pdsm {

// Parses, applies `overrides` (set fields of the override replace the scene's bake fields;
// used for command-line flags), loads meshes (relative paths against the scene file's folder)
// and validates. Errors: INVALID_ARGUMENT for bad input (malformed JSON, unknown field,
// missing or unreadable mesh, non-finite number, bad size, out-of-range parameter),
// NOT_FOUND when the scene file itself does not exist.
absl::StatusOr<Scene> LoadSceneFile(const std::string& path,
                                    const pdsm::v1::BakeParams& overrides = {});

// The same from an already parsed message. `source_label` prefixes messages; `base_dir`
// resolves relative mesh paths (empty: mesh paths are refused, as on the server).
absl::StatusOr<Scene> SceneFromProto(const pdsm::v1::Scene& message,
                                     const std::string& source_label,
                                     const std::string& base_dir);

}  // namespace pdsm

#endif  // PDSM_CORE_SCENE_SCENE_LOADER_H_
