// pdsm-view's command line (docs/viewer.md), parsed and checked into one struct.
#ifndef PDSM_CLIENT_VIEW_VIEW_OPTIONS_H_
#define PDSM_CLIENT_VIEW_VIEW_OPTIONS_H_

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "absl/status/statusor.h"
#include "client/service/service_connection.h"
#include "client/view/camera.h"
#include "client/view/frame_renderer.h"
#include "client/view/view_mode.h"

namespace pdsm::view {

struct DynamicObjectSpec {
  std::optional<glm::dvec4> sphere;  // centre xyz, radius (world)
  std::string mesh_path;             // else a mesh file
  glm::dmat4 world_from_object{1.0};
};

struct ViewOptions {
  std::string scene_path;
  std::string pdsm_path;  // --pdsm, or:
  ServiceFlags service;   // --server, --token-file, --tls-ca
  std::string job_id;     // --job
  bool headless = false;
  int width = 1280, height = 720;
  std::string screenshot_path;   // --screenshot
  std::string attenuation_path;  // --save-attenuation (PFM)
  ViewMode mode = ViewMode::kPdsm;
  std::vector<ViewMode> compare;  // --compare: tiles these modes into the screenshot
  int compare_columns = 0;        // 0: all in one row up to 4, then rows of 4
  std::optional<Camera> camera;
  RenderSettings render;
  std::vector<DynamicObjectSpec> objects;
  int frames = 0;        // window: render this many frames, screenshot, exit
  int bench_frames = 0;  // headless: time this many frames of each mode
  bool allow_mismatch = false;
  std::string light;           // --light: of a scene and PDSM of several lights
  std::string shadowmask_dir;  // --shadowmask: the folder `pdsm shadowmask` wrote
  bool partial = false;        // --server, headless: the tiles finished now, no waiting
  // --cache-mib: the PDSM's tiles kept in memory once read. Less than `pdsm query`'s default:
  // the tiles on screen are on the GPU already, the cache only spares re-reads of tiles a
  // turn of the camera evicted.
  int64_t cache_bytes = int64_t{64} << 20;
  bool verbose = false;
};

// Parses argv. Returns the options, or: INVALID_ARGUMENT naming the flag; or a status with
// code CANCELLED and the help/usage text as message when --help was asked (exit 0).
absl::StatusOr<ViewOptions> ParseViewOptions(int argc, char** argv);

}  // namespace pdsm::view

#endif  // PDSM_CLIENT_VIEW_VIEW_OPTIONS_H_
