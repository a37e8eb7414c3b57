// pdsm-view: looks at a PDSM bake on the GPU. docs/viewer.md.
// The program: parses the flags, loads the scene and the PDSM, then runs headless (OSMesa,
// headless_app.cc) or in a window (GLFW, window_app.cc; only this executable links GLFW).
#include <cstdio>
#include <string>

#include "client/cli_common.h"
#include "client/view/view_app.h"
#include "core/util/termination_cleanup.h"
#include "spdlog/sinks/stdout_color_sinks.h"
#include "spdlog/spdlog.h"

namespace pdsm::view {

int RunViewer(int argc, char** argv) {
  absl::StatusOr<ViewOptions> options = ParseViewOptions(argc, argv);
  if (!options.ok()) {
    if (options.status().code() == absl::StatusCode::kCancelled) {  // --help, --version
      std::printf("%s", std::string(options.status().message()).c_str());
      return kExitOk;
    }
    std::fprintf(stderr, "pdsm-view: %s\n", std::string(options.status().message()).c_str());
    return kExitBadInput;
  }
  // Logs (warnings, GL details) go to stderr: stdout carries the tile order and file names.
  spdlog::set_default_logger(spdlog::stderr_color_mt("pdsm-view"));
  spdlog::set_level(options->verbose ? spdlog::level::debug
                                     : spdlog::level::warn);  // -v: GL details
  absl::StatusOr<ViewScene> scene = LoadViewScene(*options);
  absl::Status status = scene.status();
  if (status.ok()) {
    status = options->headless ? RunHeadless(*options, *scene) : RunWindow(*options, *scene);
  }
  if (!status.ok()) {
    std::fprintf(stderr, "pdsm-view: %s\n", std::string(status.message()).c_str());
    return ExitCodeFor(status);
  }
  return kExitOk;
}

}  // namespace pdsm::view

int main(int argc, char** argv) {
  // Ctrl-C or a kill while a screenshot is written leaves no temporary file.
  pdsm::RemoveTempFilesOnTerminationSignals();
  return pdsm::view::RunViewer(argc, argv);
}
