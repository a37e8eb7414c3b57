// The alpha test of an Assimp material (the rules in core/scene/mesh_file.h): which materials
// of an imported file are alpha-tested, and their masks, read once per texture and cutoff.
// Internal to core/scene (mesh_file.cc); Assimp's types stay out of every other header.
#ifndef PDSM_CORE_SCENE_MATERIAL_MASKS_H_
#define PDSM_CORE_SCENE_MATERIAL_MASKS_H_

#include <map>
#include <memory>
#include <string>
#include <tuple>
#include <vector>

#include "absl/status/statusor.h"
#include "core/scene/alpha_mask.h"

struct aiScene;

namespace pdsm::internal {

// One material's alpha test: no mask (opaque), or a mask and the UV channel it reads.
struct MaterialAlpha {
  std::shared_ptr<const AlphaMask> mask;  // null: opaque
  unsigned uv_channel = 0;
  bool needs_uvs = false;  // false for a mask that casts nowhere (no texture looked up)
};

// Reads the alpha test of every material of `scene` (imported from `path`; external textures
// are read relative to its folder). Masks that are equal (same texture, channel, cutoff and
// wrap) are one object. `blend_materials` / `translucent_materials` collect the names of the
// materials read by the warned-about rules. Errors: INVALID_ARGUMENT "<reason>" naming the
// material and texture (the caller prefixes the file).
absl::StatusOr<std::vector<MaterialAlpha>> ReadMaterialAlphas(
    const aiScene& scene, const std::string& path, std::vector<std::string>* blend_materials,
    std::vector<std::string>* translucent_materials);

}  // namespace pdsm::internal

#endif  // PDSM_CORE_SCENE_MATERIAL_MASKS_H_
