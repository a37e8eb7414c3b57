// The picture `pdsm bake` ends with (OUT.png): the scene with its baked soft shadows, seen
// from pdsm-view's default camera (camera.h), rendered headless (OSMesa) in `pdsm` mode by the
// viewer's own frame renderer, so it is exactly what `pdsm-view SCENE --pdsm OUT.exr
// --headless --screenshot` shows.
#ifndef PDSM_CLIENT_VIEW_CAMERA_VIEW_H_
#define PDSM_CLIENT_VIEW_CAMERA_VIEW_H_

#include <cstdint>
#include <memory>
#include <string>

#include "absl/status/status.h"
#include "client/view/pdsm_tile_pool.h"
#include "client/view/pdsm_tiles.h"
#include "core/scene/scene.h"
#include "core/util/file_system.h"

namespace pdsm::view {

struct CameraViewOptions {
  int width = 1280, height = 720;
};

// Renders `scene` shaded by `pdsm` (the bake of that scene) and writes a PNG to `png_path`
// (atomically; `fs` null: the real file system). The PDSM's tiles stream as in pdsm-view,
// under the default GPU budget, so a map of any size is drawn; `*pool_stats` (if given) says
// how many of the tiles it reads did not fit (drawn hatched). Errors: UNAVAILABLE
// when no OSMesa GL 4.5 context can be made, INTERNAL for GL failures, reading a tile, the
// file's errors.
absl::Status WriteCameraView(const Scene& scene, std::shared_ptr<PdsmTiles> pdsm,
                             const std::string& png_path, const CameraViewOptions& options = {},
                             FileSystem* fs = nullptr, TilePoolStats* pool_stats = nullptr);

}  // namespace pdsm::view

#endif  // PDSM_CLIENT_VIEW_CAMERA_VIEW_H_
