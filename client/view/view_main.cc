// pdsm-view: looks at a PDSM bake on the GPU. docs/viewer.md.
#include "client/view/view_app.h"

int main(int argc, char** argv) { return pdsm::view::RunViewer(argc, argv); }
