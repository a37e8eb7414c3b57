// Lights from a mesh file (issue #16 item 1): a scene JSON's mesh entry with
// `"lightsFrom": "file"` adds the lights its file holds (as a world file's: world_file.h) to the
// scene's, moved by the entry's transform (docs/scene_format.md, "Lights from a mesh file").
// Internal to core/scene: LoadSceneFile and ParseSceneFile run it after parsing, so `pdsm bake`
// and `pdsm submit` (whose coordinator never opens a path) see the same lights.
#ifndef PDSM_CORE_SCENE_FILE_LIGHTS_H_
#define PDSM_CORE_SCENE_FILE_LIGHTS_H_

#include <string>
#include <vector>

#include "absl/status/status.h"
#include "pdsm/v1/scene.pb.h"

namespace pdsm::internal {

// For each meshes[i] with lights_from "file": reads its path's lights (relative paths against
// `scene_path`'s folder), applies the entry's transform (points as points, directions by the 3x3
// part renormalized, sizes by the cube root of its |determinant|), renames a light whose name is
// taken ("-2", "-3", ...), appends them to `message->lights` in mesh order, and clears the field.
// A one-light scene's `light` becomes lights[0] (named "light" when it had no name). The world
// file's warnings go to `warnings`. Errors (INVALID_ARGUMENT "<scene_path>: meshes[i].lightsFrom:
// ..."): a value other than "file", an entry without `path`, a file with no light to bake or
// that cannot be read. A transform that is not 0 or 16 numbers is left for the scene builder
// to report.
absl::Status AddLightsFromMeshFiles(const std::string& scene_path, pdsm::v1::Scene* message,
                                    std::vector<std::string>* warnings);

}  // namespace pdsm::internal

#endif  // PDSM_CORE_SCENE_FILE_LIGHTS_H_
