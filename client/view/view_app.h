// pdsm-view's program: loads the scene and the PDSM, then runs headless (OSMesa) or in a
// window (GLFW). Exit codes as the `pdsm` CLI: 0 success, 2 bad input (message naming the
// file and field), 1 other failures.
#ifndef PDSM_CLIENT_VIEW_VIEW_APP_H_
#define PDSM_CLIENT_VIEW_VIEW_APP_H_

#include "absl/status/status.h"
#include "client/view/frame_renderer.h"
#include "client/view/view_options.h"
#include "client/view/view_scene.h"

namespace pdsm::view {

// The whole program (view_main.cc, which links the window).
int RunViewer(int argc, char** argv);

// Loads everything the options name into a ViewScene (no GL needed).
absl::StatusOr<ViewScene> LoadViewScene(const ViewOptions& options);

// Renders the options' mode, or the --compare tiles (each labelled with its mode; spare cells
// of the last row hold a legend of the scene and its bake), into --screenshot (and the
// attenuation into --save-attenuation, single mode only); prints the tile order.
absl::Status RenderScreenshot(FrameRenderer& renderer, const ViewOptions& options,
                              const ViewScene& scene, const Camera& camera);

// --compare without --compare-columns: all in one row up to 4, else 3 or 4 per row, whichever
// leaves fewer spare cells (ties: 4).
int CompareColumns(int tiles);

absl::Status RunHeadless(const ViewOptions& options, const ViewScene& scene);
absl::Status RunWindow(const ViewOptions& options, ViewScene& scene);

}  // namespace pdsm::view

#endif  // PDSM_CLIENT_VIEW_VIEW_APP_H_
