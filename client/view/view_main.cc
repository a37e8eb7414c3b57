// pdsm-view: looks at a PDSM bake on the GPU. docs/viewer.md.
#include "client/view/view_app.h"
#include "core/util/termination_cleanup.h"

int main(int argc, char** argv) {
  // Ctrl-C or a kill while a screenshot is written leaves no temporary file.
  pdsm::RemoveTempFilesOnTerminationSignals();
  return pdsm::view::RunViewer(argc, argv);
}
