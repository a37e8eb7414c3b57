// `pdsm-view --mode shadowmask`: the textures `pdsm shadowmask` wrote (client/export/shadowmask.h)
// put back on the receivers they were made for, so that what an engine would show can be set
// beside the PDSM it came from.
//
// The receivers come from the scene file again (client/export/receiver_objects.h: the same
// objects, names and UV sets the command used); each object's texture is the file
// DIR/NAME-shadowmaskG.exr whose pdsmShadowmask attribute names the viewer's light.
#ifndef PDSM_CLIENT_VIEW_SHADOWMASK_TEXTURES_H_
#define PDSM_CLIENT_VIEW_SHADOWMASK_TEXTURES_H_

#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "client/view/view_scene.h"
#include "core/geometry/light_frame.h"

namespace pdsm::view {

// The light a texture channel must name for the viewer's light `light_name` (Scene::light_name
// after OneLight): a sphere light's face "bulb@-z" is shaded with the channel of "bulb" (the
// texture holds the whole light; the pdsm mode shows that face's part).
std::string ShadowmaskLightName(const std::string& light_name);

// The receivers of the scene at `scene_path` with their textures from folder `dir`, for the
// light `light_name` ("" for a scene's single unnamed light), placed in light space by `frame`.
// Objects without a texture file are listed in `missing` (they are drawn with the PDSM).
// Errors: those of LoadReceiverObjects and ReadShadowmaskExr (naming the file); NOT_FOUND
// naming `dir` when no object has a texture there; INVALID_ARGUMENT naming the textures of an
// object when none of them holds the light.
absl::StatusOr<std::vector<ShadowmaskedMesh>> LoadShadowmaskTextures(
    const std::string& scene_path, const std::string& dir, const std::string& light_name,
    const LightFrame& frame, std::vector<std::string>* missing);

}  // namespace pdsm::view

#endif  // PDSM_CLIENT_VIEW_SHADOWMASK_TEXTURES_H_
