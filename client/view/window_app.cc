// Window runs: GLFW context (GL 4.5 core), orbit camera, keys to switch modes,
// toggle bilinear filtering and move the dynamic objects. Keys: docs/viewer.md.
// The window is the viewer's own platform part (only it opens one); the headless context is
// gl/platform/osmesa_context.h. Either way GL is called through gl::GlFunctions.
#define GLFW_INCLUDE_NONE  // GL declarations come from gl/ (glcorearb.h)
#include <GLFW/glfw3.h>

#include <chrono>
#include <cstdio>
#include <memory>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "client/view/image_io.h"
#include "client/view/job_follower.h"
#include "client/view/view_app.h"
#include "gl/gl_functions.h"
#include "spdlog/spdlog.h"

namespace pdsm::view {
namespace {

struct GlfwDeleter {
  void operator()(GLFWwindow* window) const { glfwDestroyWindow(window); }
};
using WindowPtr = std::unique_ptr<GLFWwindow, GlfwDeleter>;

// glfwInit / glfwTerminate as an owner.
class GlfwLibrary {
 public:
  GlfwLibrary() : ok_(glfwInit() == GLFW_TRUE) {}
  ~GlfwLibrary() {
    if (ok_) glfwTerminate();
  }
  bool ok() const { return ok_; }

 private:
  bool ok_;
};

struct WindowState {
  ViewScene* scene = nullptr;
  FrameRenderer* renderer = nullptr;
  Camera camera, home;
  ViewMode mode = ViewMode::kPdsm;
  bool dragging = false;
  double last_x = 0, last_y = 0;
  double step = 0.1;  // world units per arrow key press
  int screenshots = 0;
  bool screenshot_requested = false;
};

WindowState& State(GLFWwindow* window) {
  return *static_cast<WindowState*>(glfwGetWindowUserPointer(window));
}

void MoveObjects(WindowState& s, const glm::dvec3& delta) {
  if (s.scene->dynamic_objects.empty()) {
    spdlog::warn("no dynamic object to move: add --sphere X,Y,Z,R or --object MESH");
    return;
  }
  // The first object moves; its shadow maps (shadow-map modes) are redrawn next frame.
  s.scene->dynamic_objects.front().world_from_object[3] += glm::dvec4(delta, 0.0);
  s.renderer->InvalidateShadowMaps();
}

void OnKey(GLFWwindow* window, int key, int, int action, int) {
  if (action != GLFW_PRESS && action != GLFW_REPEAT) return;
  WindowState& s = State(window);
  // Arrows move in the camera's horizontal frame, PgUp/PgDn along world up.
  glm::dvec3 forward = s.camera.target_world - s.camera.eye_world;
  forward.y = 0;
  forward = glm::length(forward) > 0 ? glm::normalize(forward) : glm::dvec3(0, 0, -1);
  const glm::dvec3 right = glm::cross(forward, glm::dvec3(0, 1, 0));
  // Every light at once is pdsm mode's alone: the other modes render one light's maps.
  if (key >= GLFW_KEY_1 && key <= GLFW_KEY_7 && s.scene->every_light.empty()) {
    s.mode = kAllModes[key - GLFW_KEY_1];
  }
  if (key == GLFW_KEY_8 && !s.scene->shadowmasked.empty()) s.mode = ViewMode::kShadowmask;
  switch (key) {
    case GLFW_KEY_ESCAPE:
    case GLFW_KEY_Q:
      glfwSetWindowShouldClose(window, GLFW_TRUE);
      break;
    case GLFW_KEY_B:
      s.renderer->settings().bilinear = !s.renderer->settings().bilinear;
      break;
    case GLFW_KEY_UP:
      MoveObjects(s, s.step * forward);
      break;
    case GLFW_KEY_DOWN:
      MoveObjects(s, -s.step * forward);
      break;
    case GLFW_KEY_RIGHT:
      MoveObjects(s, s.step * right);
      break;
    case GLFW_KEY_LEFT:
      MoveObjects(s, -s.step * right);
      break;
    case GLFW_KEY_PAGE_UP:
      MoveObjects(s, glm::dvec3(0, s.step, 0));
      break;
    case GLFW_KEY_PAGE_DOWN:
      MoveObjects(s, glm::dvec3(0, -s.step, 0));
      break;
    case GLFW_KEY_R:
      s.camera = s.home;
      break;
    case GLFW_KEY_C:
      std::printf("--camera %s\n", FormatCamera(s.camera).c_str());
      break;
    case GLFW_KEY_P:
      s.screenshot_requested = true;
      break;
    default:
      break;
  }
}

void OnMouseButton(GLFWwindow* window, int button, int action, int) {
  WindowState& s = State(window);
  if (button != GLFW_MOUSE_BUTTON_LEFT) return;
  s.dragging = action == GLFW_PRESS;
  glfwGetCursorPos(window, &s.last_x, &s.last_y);
}

void OnCursor(GLFWwindow* window, double x, double y) {
  WindowState& s = State(window);
  if (!s.dragging) return;
  Orbit(&s.camera, -0.008 * (x - s.last_x), 0.008 * (y - s.last_y));
  s.last_x = x;
  s.last_y = y;
}

void OnScroll(GLFWwindow* window, double, double dy) {
  Zoom(&State(window).camera, dy > 0 ? 0.9 : 1.0 / 0.9);
}

absl::StatusOr<WindowPtr> OpenWindow(const ViewOptions& options) {
  glfwDefaultWindowHints();
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 4);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 5);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  GLFWwindow* window =
      glfwCreateWindow(options.width, options.height, "pdsm-view", nullptr, nullptr);
  if (window != nullptr) return WindowPtr(window);
  const char* description = nullptr;
  glfwGetError(&description);
  return absl::UnavailableError(absl::StrCat(
      "cannot open a GL 4.5 core window: ", description ? description : "unknown GLFW error",
      " (no display? use --headless)"));
}

// Shows a newer PDSM of the followed job; the final one is checked against the scene.
absl::Status AdoptPdsm(const ViewOptions& options, PartialPdsm pdsm, ViewScene& scene,
                       FrameRenderer& renderer) {
  if (pdsm.complete()) {
    absl::Status s = CheckPdsmMatchesScene(scene.scene, pdsm.image.header, "job " + options.job_id);
    if (!s.ok() && !options.allow_mismatch) return s;
  }
  scene.pdsm = PdsmTiles::FromImage(std::move(pdsm.image), std::move(pdsm.pending));
  return renderer.ReplacePdsm();
}

absl::Status SaveScreenshot(FrameRenderer& renderer, const std::string& path) {
  absl::StatusOr<Frame> frame = renderer.ReadFrame();
  if (!frame.ok()) return frame.status();
  if (absl::Status s = WritePng(path, {frame->width, frame->height, frame->rgb}); !s.ok()) {
    return s;
  }
  std::printf("wrote %s (%dx%d)\n", path.c_str(), frame->width, frame->height);
  return absl::OkStatus();
}

}  // namespace

absl::Status RunWindow(const ViewOptions& options, ViewScene& scene) {
  GlfwLibrary glfw;
  if (!glfw.ok()) return absl::UnavailableError("glfwInit failed (no display? use --headless)");
  absl::StatusOr<WindowPtr> window = OpenWindow(options);
  if (!window.ok()) return window.status();
  glfwMakeContextCurrent(window->get());
  glfwSwapInterval(1);
  absl::StatusOr<gl::GlFunctions> gl = gl::GlFunctions::Load(&glfwGetProcAddress);
  if (!gl.ok()) return gl.status();
  absl::StatusOr<std::unique_ptr<FrameRenderer>> renderer =
      FrameRenderer::Create(*gl, &scene, options.render);
  if (!renderer.ok()) return renderer.status();

  WindowState state;
  state.scene = &scene;
  state.renderer = renderer->get();
  state.home = state.camera =
      options.camera ? *options.camera
                     : DefaultCamera(scene, static_cast<double>(options.width) / options.height);
  state.mode = options.mode;
  state.step = 0.02 * glm::length(scene.bounds_max_world - scene.bounds_min_world);
  glfwSetWindowUserPointer(window->get(), &state);
  glfwSetKeyCallback(window->get(), OnKey);
  glfwSetMouseButtonCallback(window->get(), OnMouseButton);
  glfwSetCursorPosCallback(window->get(), OnCursor);
  glfwSetScrollCallback(window->get(), OnScroll);

  // --job: tiles appear as the service finishes them, then the final PDSM.
  std::unique_ptr<JobFollower> follower;
  pdsm::v1::Job job;
  if (scene.plan != nullptr) {
    absl::StatusOr<std::unique_ptr<JobFollower>> f =
        JobFollower::Create(options.service, options.job_id, options.light, scene.plan.get());
    if (!f.ok()) return f.status();
    follower = *std::move(f);
    follower->Start(/*interval_ms=*/300);
  }
  bool follow_error_reported = false;
  absl::Status follow_error;
  bool final_shown = follower == nullptr;  // --frames counts from here on (scripted runs)
  int frames_counted = 0;

  absl::Status status;
  while (!glfwWindowShouldClose(window->get())) {
    if (follower != nullptr) {
      if (std::optional<JobSnapshot> snapshot = follower->Take()) {
        job = snapshot->job;
        if (snapshot->pdsm) {
          const bool complete = snapshot->pdsm->complete();
          status = AdoptPdsm(options, *std::move(snapshot->pdsm), scene, **renderer);
          if (!status.ok()) break;
          final_shown = final_shown || complete;
        }
      }
      if (absl::Status e = follower->error(); !e.ok() && !follow_error_reported) {
        spdlog::error("{}", std::string(e.message()));  // keep showing what arrived
        follow_error_reported = true;
        follow_error = e;
      }
    }
    int width = 0, height = 0;
    glfwGetFramebufferSize(window->get(), &width, &height);
    if (width > 0 && height > 0) {
      status = (*renderer)->Render(state.mode, state.camera, width, height);
      if (!status.ok()) break;
      (*renderer)->BlitToScreen(width, height);
      const FrameTimings& t = (*renderer)->last_timings();
      const std::string job_line =
          follower == nullptr
              ? ""
              : absl::StrFormat("  job %s: %d/%d tiles", pdsm::v1::JobState_Name(job.state()),
                                job.tiles_done(), job.tiles_total());
      glfwSetWindowTitle(
          window->get(),
          absl::StrFormat("pdsm-view: %s%s  %.1f ms%s  [1-7%s mode, B bilinear, "
                          "arrows/PgUp/PgDn move, P screenshot]",
                          ModeName(state.mode),
                          (*renderer)->settings().bilinear ? "" : " (nearest)",
                          1e3 * (t.shade_seconds + t.cpu_seconds + t.shadow_map_seconds), job_line,
                          state.scene->shadowmasked.empty() ? "" : ", 8 shadowmask")
              .c_str());
    }
    if (state.screenshot_requested) {
      state.screenshot_requested = false;
      status = SaveScreenshot(**renderer, absl::StrCat("pdsm-view-", state.screenshots++, ".png"));
      if (!status.ok()) break;
    }
    glfwSwapBuffers(window->get());
    // --frames with --job: N frames of the finished job (a script wants the final image), or
    // the error that stopped following it as the exit status.
    if (options.frames > 0 && (final_shown || !follow_error.ok()) &&
        ++frames_counted >= options.frames) {
      if (!follow_error.ok()) {
        status = follow_error;
      } else if (!options.screenshot_path.empty()) {
        status = SaveScreenshot(**renderer, options.screenshot_path);
      }
      break;
    }
    glfwPollEvents();
  }
  renderer->reset();  // GL objects go while the context is current
  return status;
}

}  // namespace pdsm::view
