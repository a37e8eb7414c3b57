#include "client/view/camera_view.h"

#include <memory>
#include <utility>

#include "client/view/camera.h"
#include "client/view/frame_renderer.h"
#include "client/view/image_io.h"
#include "client/view/view_scene.h"
#include "gl/gl_functions.h"
#include "gl/platform/osmesa_context.h"

namespace pdsm::view {

absl::Status WriteCameraView(const Scene& scene, std::shared_ptr<PdsmTiles> pdsm,
                             const std::string& png_path, const CameraViewOptions& options,
                             FileSystem* fs, TilePoolStats* pool_stats) {
  ViewScene view;
  view.scene = scene;
  view.pdsm = std::move(pdsm);
  PrepareViewScene(&view);
  absl::StatusOr<gl::OsMesaContext> context = gl::OsMesaContext::Create();
  if (!context.ok()) return context.status();
  absl::StatusOr<gl::GlFunctions> gl = gl::GlFunctions::Load(&gl::OsMesaContext::GetProcAddress);
  if (!gl.ok()) return gl.status();
  absl::StatusOr<Frame> frame;
  {
    // The renderer's GL objects go before the context (this block).
    absl::StatusOr<std::unique_ptr<FrameRenderer>> renderer =
        FrameRenderer::Create(*gl, &view, RenderSettings{});
    if (!renderer.ok()) return renderer.status();
    const Camera camera = DefaultCamera(view, static_cast<double>(options.width) / options.height);
    if (absl::Status s =
            (*renderer)->Render(ViewMode::kPdsm, camera, options.width, options.height);
        !s.ok()) {
      return s;
    }
    frame = (*renderer)->ReadFrame();
    if (pool_stats) *pool_stats = (*renderer)->pdsm_pool_stats();
  }
  if (!frame.ok()) return frame.status();
  return WritePng(png_path, {frame->width, frame->height, std::move(frame->rgb)}, fs);
}

}  // namespace pdsm::view
