// `cpu` mode: the PDSM evaluated per screen pixel by the CPU code of `pdsm query`
// (QueryAttenuation, through the tiles the viewer reads), on the light-space positions of a
// G-buffer read back from the GPU. It is the reference the GPU path (shade.frag) is tested
// against.
#ifndef PDSM_CLIENT_VIEW_CPU_ATTENUATION_H_
#define PDSM_CLIENT_VIEW_CPU_ATTENUATION_H_

#include <vector>

#include "absl/status/statusor.h"
#include "client/view/pdsm_tiles.h"

namespace pdsm::view {

// `gbuffer`: width * height RGBA float32, (x, y, z) light space of the PDSM's frame and alpha
// 1 where a surface was drawn. Returns width * height attenuations in the same order: NaN for
// the background and outside the PDSM frustum; `pending_value` where one of the (up to 4) PDSM
// pixels the lookup blends is not baked yet, as the GPU path does. Uses every core (rows are
// independent). Errors: reading a tile of the file.
absl::StatusOr<std::vector<float>> EvaluateAttenuationImage(PdsmTiles& pdsm,
                                                            const std::vector<float>& gbuffer,
                                                            int width, int height,
                                                            float pending_value);

}  // namespace pdsm::view

#endif  // PDSM_CLIENT_VIEW_CPU_ATTENUATION_H_
