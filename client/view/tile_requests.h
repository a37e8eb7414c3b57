// The PDSM tiles a frame reads (the feedback pass of the viewer's tile streaming, issue #12):
// from the light-space position of every pixel's surface, the tiles whose pixels the shade
// pass's PDSM lookup touches, each with the number of screen pixels that need it.
#ifndef PDSM_CLIENT_VIEW_TILE_REQUESTS_H_
#define PDSM_CLIENT_VIEW_TILE_REQUESTS_H_

#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "client/view/pdsm_tile_pool.h"
#include "core/pdsm/pdsm_image.h"

namespace pdsm::view {

// `positions_light`: (x, y, z, w) per screen pixel, light space, w = 0 for no surface (the
// G-buffer). A pixel outside the PDSM's frustum (as shade.frag decides) needs no tile. Each
// pixel asks for the tiles of every PDSM pixel within 1.5 pixels of where it projects: the 4
// the bilinear blend reads and the nearest one, whatever float rounding the GPU does. Ordered
// row-major by tile, each for part `part`. `light_from_view` (if given) takes the positions
// into this part's light space first (another light of the file than the view's).
// REQUIRES: header.tile_size > 0.
std::vector<TileRequest> TilesSeen(const PdsmHeader& header, std::span<const float> positions_light,
                                   int part = 0, const glm::dmat4* light_from_view = nullptr);

}  // namespace pdsm::view

#endif  // PDSM_CLIENT_VIEW_TILE_REQUESTS_H_
