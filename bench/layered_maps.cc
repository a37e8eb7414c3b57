// Several light samples per draw (issue #11 item 6, docs/performance.md "Beyond the limit"):
// does drawing K samples' shadow maps in one instanced draw, each instance into its own layer
// of a layered render target, cost less CPU per map than the bake's renderer drawing them one
// at a time (the limit of `pdsm-bench-limit`)? llvmpipe runs the vertex shader once per vertex
// and instance, so what could be shared is the GL front end, the draw setup and the binning
// passes; this measures how much that is.
//
// The layered maps are the renderer's maps: the same matrices (ShadowMapClipFromLight), the
// same fragment shader, the same depth test, the same flush size in triangles binned. Each
// run's maps are compared texel by texel with the renderer's, and the differences printed.
// Two ways to pick the layer:
//   vs  the vertex shader writes gl_Layer = gl_InstanceID (GL_ARB_shader_viewport_layer_array);
//   gs  a geometry shader with K invocations, gl_Layer = gl_InvocationID (no instancing).
// Runs the renderer and each K alternately `--repeat` times in this one process (threads as the
// bake: one context each, samples dealt round-robin) and prints CPU seconds and their medians.
//
// Usage: pdsm-bench-layered SCENE.json [--resolution N] [--samples N] [--sm-resolution N]
//        [--threads N] [--repeat N] [--layers K[,K...]] [--mode vs|gs]

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "absl/synchronization/mutex.h"
#include "bench/bench_support.h"
#include "core/bake/bake_plan.h"
#include "core/scene/scene_loader.h"
#include "core/util/malloc_arenas.h"
#include "core/util/work_queue.h"
#include "gl/gl_functions.h"
#include "gl/gl_objects.h"
#include "gl/gl_program.h"
#include "gl/platform/osmesa_context.h"
#include "worker/bake_task.h"
#include "worker/shadow_map_renderer.h"
#include "worker/shadow_map_shaders.h"  // generated: the bake's GLSL, whose fragment shader is reused

namespace pdsm {
namespace {

using bench::CpuSeconds;
using bench::FullWindow;
using bench::Median;

constexpr int kMaxLayers = 16;
// As worker/shadow_map_renderer.cc: triangles binned between flushes (here counted over the
// instances: a draw of K instances flushes every kTrianglesPerFlush / K triangles).
constexpr int kTrianglesPerFlush = 16384;

enum class LayerMode { kVertexShader, kGeometryShader };

constexpr char kLayeredVertexShader[] = R"glsl(#version 450 core
#extension GL_ARB_shader_viewport_layer_array : require
layout(location = 0) in vec3 position_light;
uniform mat4 clip_from_light[16];
out float z_light;
void main() {
  z_light = position_light.z;
  gl_Layer = gl_InstanceID;
  gl_Position = clip_from_light[gl_InstanceID] * vec4(position_light, 1.0);
}
)glsl";

constexpr char kPassThroughVertexShader[] = R"glsl(#version 450 core
layout(location = 0) in vec3 position_light;
out vec3 position_gs;
void main() { position_gs = position_light; }
)glsl";

// LAYERS is defined in front of it (the invocation count must be a constant).
constexpr char kLayeredGeometryShader[] = R"glsl(
layout(triangles, invocations = LAYERS) in;
layout(triangle_strip, max_vertices = 3) out;
in vec3 position_gs[];
uniform mat4 clip_from_light[16];
uniform int layers_used;
out float z_light;
void main() {
  if (gl_InvocationID >= layers_used) return;
  for (int i = 0; i < 3; ++i) {
    z_light = position_gs[i].z;
    gl_Layer = gl_InvocationID;
    gl_Position = clip_from_light[gl_InvocationID] * vec4(position_gs[i], 1.0);
    EmitVertex();
  }
  EndPrimitive();
}
)glsl";

// The GL 4.x entry points the project's table does not load.
struct LayeredEntryPoints {
  PFNGLDRAWELEMENTSINSTANCEDPROC DrawElementsInstanced = nullptr;
  PFNGLFRAMEBUFFERTEXTUREPROC FramebufferTexture = nullptr;
  PFNGLUNIFORMMATRIX4FVPROC UniformMatrix4fv = nullptr;
};

absl::StatusOr<gl::Program> LinkLayered(const gl::GlFunctions& gl, LayerMode mode, int layers) {
  const auto compile = [&](GLenum type, const std::string& source) -> absl::StatusOr<GLuint> {
    const GLuint shader = gl.CreateShader(type);
    const char* text = source.c_str();
    gl.ShaderSource(shader, 1, &text, nullptr);
    gl.CompileShader(shader);
    GLint ok = 0;
    gl.GetShaderiv(shader, GL_COMPILE_STATUS, &ok);
    if (!ok) {
      char log[4096] = {};
      gl.GetShaderInfoLog(shader, sizeof(log), nullptr, log);
      return absl::InternalError(absl::StrCat("shader: ", log));
    }
    return shader;
  };
  std::vector<GLuint> shaders;
  if (mode == LayerMode::kVertexShader) {
    absl::StatusOr<GLuint> vs = compile(GL_VERTEX_SHADER, kLayeredVertexShader);
    if (!vs.ok()) return vs.status();
    shaders.push_back(*vs);
  } else {
    absl::StatusOr<GLuint> vs = compile(GL_VERTEX_SHADER, kPassThroughVertexShader);
    if (!vs.ok()) return vs.status();
    absl::StatusOr<GLuint> gs = compile(
        GL_GEOMETRY_SHADER,
        absl::StrCat("#version 450 core\n#define LAYERS ", layers, "\n", kLayeredGeometryShader));
    if (!gs.ok()) return gs.status();
    shaders.push_back(*vs);
    shaders.push_back(*gs);
  }
  absl::StatusOr<GLuint> fs = compile(GL_FRAGMENT_SHADER, kShadowMapFragmentShader);
  if (!fs.ok()) return fs.status();
  shaders.push_back(*fs);
  gl::Program program = gl::MakeProgram(gl);
  for (GLuint s : shaders) gl.AttachShader(program.name(), s);
  gl.LinkProgram(program.name());
  for (GLuint s : shaders) gl.DeleteShader(s);
  GLint linked = 0;
  gl.GetProgramiv(program.name(), GL_LINK_STATUS, &linked);
  if (!linked) {
    char log[4096] = {};
    gl.GetProgramInfoLog(program.name(), sizeof(log), nullptr, log);
    return absl::InternalError(absl::StrCat("link: ", log));
  }
  return program;
}

// Renders up to `layers` maps of one window per draw. One thread at a time.
class LayeredRenderer {
 public:
  static absl::StatusOr<std::unique_ptr<LayeredRenderer>> Create(const BakePlan& plan,
                                                                 LayerMode mode, int layers,
                                                                 const ShadowMapWindow& window) {
    absl::StatusOr<gl::OsMesaContext> context = gl::OsMesaContext::Create();
    if (!context.ok()) return context.status();
    absl::StatusOr<gl::GlFunctions> gl = gl::GlFunctions::Load(&gl::OsMesaContext::GetProcAddress);
    if (!gl.ok()) return gl.status();
    auto r = std::unique_ptr<LayeredRenderer>(new LayeredRenderer(*std::move(context), *gl));
    if (absl::Status s = r->Init(plan, mode, layers, window); !s.ok()) return s;
    return r;
  }

  ~LayeredRenderer() { (void)context_.MakeCurrent(); }

  // Renders the cameras' maps (at most `layers`; all with the window given to Create) into
  // `out[i]`, row-major as ShadowMapRenderer::Render writes them.
  absl::Status Render(std::span<const ShadowMapCamera> cameras,
                      std::vector<std::vector<float>>* out) {
    const GLsizei n = static_cast<GLsizei>(cameras.size());
    gl_.BindFramebuffer(GL_FRAMEBUFFER, draw_fb_.name());
    gl_.Viewport(0, 0, window_.width, window_.height);
    const float no_caster[4] = {std::numeric_limits<float>::infinity(), 0, 0, 0};
    const float beyond_everything = 0.0f;
    gl_.ClearBufferfv(GL_COLOR, 0, no_caster);
    gl_.ClearBufferfv(GL_DEPTH, 0, &beyond_everything);
    std::array<float, 16 * kMaxLayers> matrices{};
    for (GLsizei i = 0; i < n; ++i) {
      const std::array<float, 16> m = ShadowMapClipFromLight(cameras[i], window_, true);
      std::copy(m.begin(), m.end(), matrices.begin() + 16 * i);
    }
    ep_.UniformMatrix4fv(clip_from_light_, n, GL_FALSE, matrices.data());
    if (mode_ == LayerMode::kGeometryShader) gl_.Uniform1i(layers_used_, n);
    const GLsizei per_flush =
        3 * std::max<GLsizei>(256, kTrianglesPerFlush / std::max<GLsizei>(1, n));
    for (GLsizei first = 0; first < index_count_; first += per_flush) {
      const GLsizei count = std::min(per_flush, index_count_ - first);
      const void* offset = reinterpret_cast<const void*>(static_cast<size_t>(first) * 4);
      if (mode_ == LayerMode::kVertexShader) {
        ep_.DrawElementsInstanced(GL_TRIANGLES, count, GL_UNSIGNED_INT, offset, n);
      } else {
        gl_.DrawElements(GL_TRIANGLES, count, GL_UNSIGNED_INT, offset);
      }
      gl_.Flush();
    }
    gl_.BindFramebuffer(GL_READ_FRAMEBUFFER, read_fb_.name());
    out->resize(n);
    for (GLsizei i = 0; i < n; ++i) {
      gl_.FramebufferTextureLayer(GL_READ_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, color_.name(), 0, i);
      gl_.ReadBuffer(GL_COLOR_ATTACHMENT0);
      (*out)[i].resize(static_cast<size_t>(window_.width) * window_.height);
      gl_.ReadPixels(0, 0, window_.width, window_.height, GL_RED, GL_FLOAT, (*out)[i].data());
    }
    return gl::CheckGlError(gl_, "layered render");
  }

 private:
  LayeredRenderer(gl::OsMesaContext context, const gl::GlFunctions& gl)
      : context_(std::move(context)), gl_(gl) {}

  absl::Status Init(const BakePlan& plan, LayerMode mode, int layers,
                    const ShadowMapWindow& window) {
    mode_ = mode;
    window_ = window;
    const auto load = [](const char* name) { return gl::OsMesaContext::GetProcAddress(name); };
    ep_.DrawElementsInstanced =
        reinterpret_cast<PFNGLDRAWELEMENTSINSTANCEDPROC>(load("glDrawElementsInstanced"));
    ep_.FramebufferTexture =
        reinterpret_cast<PFNGLFRAMEBUFFERTEXTUREPROC>(load("glFramebufferTexture"));
    ep_.UniformMatrix4fv = gl_.UniformMatrix4fv;
    absl::StatusOr<gl::Program> program = LinkLayered(gl_, mode, layers);
    if (!program.ok()) return program.status();
    program_ = *std::move(program);
    gl_.UseProgram(program_.name());
    clip_from_light_ = gl_.GetUniformLocation(program_.name(), "clip_from_light");
    layers_used_ = gl_.GetUniformLocation(program_.name(), "layers_used");
    const ShadowMapCamera camera = BakeCamera(plan);
    gl_.Uniform1f(gl_.GetUniformLocation(program_.name(), "depth_bias"),
                  static_cast<float>(camera.depth_bias));
    gl_.Uniform1f(gl_.GetUniformLocation(program_.name(), "slope_bias"),
                  static_cast<float>(camera.slope_bias));
    gl_.Uniform1f(gl_.GetUniformLocation(program_.name(), "footprint_scale"),
                  static_cast<float>(camera.footprint_scale));
    gl_.Uniform1i(gl_.GetUniformLocation(program_.name(), "orthographic"),
                  camera.projection == Projection::kOrthographic);
    gl_.Uniform1f(gl_.GetUniformLocation(program_.name(), "z_clip_near"),
                  static_cast<float>(camera.z_clip_near));
    gl_.Uniform1f(gl_.GetUniformLocation(program_.name(), "z_clip_far"),
                  static_cast<float>(camera.z_clip_far));

    vertex_array_ = gl::MakeVertexArray(gl_);
    vertex_buffer_ = gl::MakeBuffer(gl_);
    index_buffer_ = gl::MakeBuffer(gl_);
    gl_.BindVertexArray(vertex_array_.name());
    gl_.BindBuffer(GL_ARRAY_BUFFER, vertex_buffer_.name());
    gl_.BufferData(GL_ARRAY_BUFFER, plan.casters.positions.size() * sizeof(glm::vec3),
                   plan.casters.positions.data(), GL_STATIC_DRAW);
    gl_.EnableVertexAttribArray(0);
    gl_.VertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, sizeof(glm::vec3), nullptr);
    gl_.BindBuffer(GL_ELEMENT_ARRAY_BUFFER, index_buffer_.name());
    gl_.BufferData(GL_ELEMENT_ARRAY_BUFFER, plan.casters.indices.size() * 4,
                   plan.casters.indices.data(), GL_STATIC_DRAW);
    index_count_ = static_cast<GLsizei>(plan.casters.indices.size());

    color_ = gl::MakeTexture(gl_);
    depth_ = gl::MakeTexture(gl_);
    for (const auto& [texture, internal, format] :
         {std::tuple{&color_, GL_R32F, GL_RED},
          std::tuple{&depth_, GL_DEPTH_COMPONENT32F, GL_DEPTH_COMPONENT}}) {
      gl_.BindTexture(GL_TEXTURE_2D_ARRAY, texture->name());
      gl_.TexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
      gl_.TexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
      gl_.TexImage3D(GL_TEXTURE_2D_ARRAY, 0, internal, window.width, window.height, layers, 0,
                     format, GL_FLOAT, nullptr);
    }
    draw_fb_ = gl::MakeFramebuffer(gl_);
    read_fb_ = gl::MakeFramebuffer(gl_);
    gl_.BindFramebuffer(GL_FRAMEBUFFER, draw_fb_.name());
    ep_.FramebufferTexture(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, color_.name(), 0);
    ep_.FramebufferTexture(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, depth_.name(), 0);
    const GLenum draw_buffer = GL_COLOR_ATTACHMENT0;
    gl_.DrawBuffers(1, &draw_buffer);
    if (gl_.CheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
      return absl::InternalError("layered framebuffer incomplete");
    }
    gl_.ClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
    gl_.Enable(GL_DEPTH_TEST);
    gl_.DepthFunc(GL_GREATER);
    gl_.DepthMask(GL_TRUE);
    gl_.Disable(GL_CULL_FACE);
    gl_.Disable(GL_BLEND);
    gl_.PixelStorei(GL_PACK_ALIGNMENT, 4);
    return gl::CheckGlError(gl_, "setting up the layered renderer");
  }

  gl::OsMesaContext context_;  // first: destroyed after the GL objects
  gl::GlFunctions gl_;
  LayeredEntryPoints ep_;
  LayerMode mode_ = LayerMode::kVertexShader;
  ShadowMapWindow window_;
  gl::Program program_;
  GLint clip_from_light_ = -1, layers_used_ = -1;
  gl::VertexArray vertex_array_;
  gl::Buffer vertex_buffer_, index_buffer_;
  GLsizei index_count_ = 0;
  gl::Texture color_, depth_;
  gl::Framebuffer draw_fb_, read_fb_;
};

struct Options {
  std::string scene_path;
  pdsm::v1::BakeParams overrides;
  int threads = 0, repeat = 3;
  std::vector<int> layers = {4, 8};
  LayerMode mode = LayerMode::kVertexShader;
};

// What a run produced: the maps of the samples a thread was dealt, kept only for the check.
struct Maps {
  std::vector<std::vector<float>> of_sample;
};

// Renders every sample's full map on `threads` threads: layers == 0 with ShadowMapRenderer,
// one map per draw (the limit); otherwise `layers` maps per layered draw. Samples are dealt
// to threads in runs of max(1, layers). CPU seconds of the whole process.
absl::StatusOr<double> RenderAll(const BakePlan& plan, const Options& o, int layers, Maps* maps) {
  const ShadowMapWindow window = FullWindow(plan);
  const int threads = o.threads;
  const int run = std::max(1, layers);
  maps->of_sample.assign(plan.samples.size(), {});
  WorkQueue queue(threads);
  absl::Mutex mu;
  absl::Status failure;
  const double cpu = CpuSeconds();
  for (int t = 0; t < threads; ++t) {
    queue.Post([&, t] {
      absl::Status s = [&]() -> absl::Status {
        ShadowMapCamera camera = BakeCamera(plan);
        camera.window = window;
        if (layers == 0) {
          absl::StatusOr<std::unique_ptr<ShadowMapRenderer>> r = ShadowMapRenderer::Create();
          if (!r.ok()) return r.status();
          if (absl::Status g = (*r)->SetGeometry(plan.casters.positions, plan.casters.indices);
              !g.ok()) {
            return g;
          }
          for (size_t k = t; k < plan.samples.size(); k += threads) {
            camera.sample = plan.samples[k];
            if (absl::Status e = (*r)->Render(camera, &maps->of_sample[k]); !e.ok()) return e;
          }
          return absl::OkStatus();
        }
        absl::StatusOr<std::unique_ptr<LayeredRenderer>> r =
            LayeredRenderer::Create(plan, o.mode, layers, window);
        if (!r.ok()) return r.status();
        std::vector<ShadowMapCamera> cameras;
        std::vector<std::vector<float>> out;
        for (size_t first = static_cast<size_t>(t) * run; first < plan.samples.size();
             first += static_cast<size_t>(threads) * run) {
          const size_t end = std::min(plan.samples.size(), first + run);
          cameras.assign(end - first, camera);
          for (size_t k = first; k < end; ++k) cameras[k - first].sample = plan.samples[k];
          if (absl::Status e = (*r)->Render(cameras, &out); !e.ok()) return e;
          for (size_t k = first; k < end; ++k) maps->of_sample[k] = std::move(out[k - first]);
        }
        return absl::OkStatus();
      }();
      absl::MutexLock lock(&mu);
      if (failure.ok()) failure = s;
    });
  }
  queue.Wait();
  if (!failure.ok()) return failure;
  return CpuSeconds() - cpu;
}

// Texels whose bits differ between two runs' maps.
int64_t DifferingTexels(const Maps& a, const Maps& b) {
  int64_t differing = 0;
  for (size_t k = 0; k < a.of_sample.size(); ++k) {
    const std::vector<float>& x = a.of_sample[k];
    const std::vector<float>& y = b.of_sample[k];
    if (x.size() != y.size()) return -1;
    for (size_t i = 0; i < x.size(); ++i) {
      differing += std::memcmp(&x[i], &y[i], sizeof(float)) != 0 ? 1 : 0;
    }
  }
  return differing;
}

bool ParseFlags(int argc, char** argv, Options* o) {
  if (argc < 2) return false;
  o->scene_path = argv[1];
  for (int i = 2; i + 1 < argc; i += 2) {
    const std::string flag = argv[i], value = argv[i + 1];
    if (flag == "--layers") {
      o->layers.clear();
      for (absl::string_view k : absl::StrSplit(value, ',')) {
        int v = 0;
        if (!absl::SimpleAtoi(k, &v) || v < 1 || v > kMaxLayers) return false;
        o->layers.push_back(v);
      }
      continue;
    }
    if (flag == "--mode") {
      if (value != "vs" && value != "gs") return false;
      o->mode = value == "vs" ? LayerMode::kVertexShader : LayerMode::kGeometryShader;
      continue;
    }
    if (bench::ApplySceneFlag(flag, value, &o->overrides)) continue;
    int v = 0;
    if (!absl::SimpleAtoi(value, &v)) return false;
    if (flag == "--threads") {
      o->threads = v;
    } else if (flag == "--repeat") {
      o->repeat = std::max(1, v);
    } else {
      return false;
    }
  }
  return true;
}

int Run(int argc, char** argv) {
  Options o;
  if (!ParseFlags(argc, argv, &o)) {
    std::fprintf(stderr,
                 "usage: pdsm-bench-layered SCENE.json [--resolution N] [--samples N] "
                 "[--sm-resolution N] [--threads N] [--repeat N] [--layers K[,K...]] "
                 "[--mode vs|gs]\n");
    return 2;
  }
  absl::StatusOr<Scene> scene = LoadSceneFile(o.scene_path, o.overrides);
  if (!scene.ok()) return std::fprintf(stderr, "%s\n", scene.status().ToString().c_str()), 2;
  absl::StatusOr<BakePlan> plan = PlanBake(*scene);
  if (!plan.ok()) return std::fprintf(stderr, "%s\n", plan.status().ToString().c_str()), 1;
  if (o.threads <= 0) o.threads = CoreCount();
  gl::ShareCoresBetweenContexts(o.threads);  // as the bake and pdsm-bench-limit
  LimitMallocArenas(o.threads);
  const ShadowMapWindow full = FullWindow(*plan);
  std::printf("%s: %zu samples, shadow maps %dx%d, %zu casters, %d threads, mode %s\n",
              scene->name.c_str(), plan->samples.size(), full.width, full.height,
              plan->casters.TriangleCount(), o.threads,
              o.mode == LayerMode::kVertexShader ? "vs (gl_Layer in the vertex shader)"
                                                 : "gs (geometry shader invocations)");
  std::vector<int> configs = {0};
  configs.insert(configs.end(), o.layers.begin(), o.layers.end());
  std::vector<std::vector<double>> cpu(configs.size());
  for (int r = 0; r < o.repeat; ++r) {
    Maps reference;
    for (size_t c = 0; c < configs.size(); ++c) {
      Maps maps;
      absl::StatusOr<double> s = RenderAll(*plan, o, configs[c], &maps);
      if (!s.ok()) return std::fprintf(stderr, "%s\n", s.status().ToString().c_str()), 1;
      cpu[c].push_back(*s);
      if (c == 0) {
        reference = std::move(maps);
        std::printf("run %d: one map per draw %.2f CPU-s", r + 1, *s);
      } else {
        std::printf("; %d per draw %.2f CPU-s (%lld texels differ)", configs[c], *s,
                    static_cast<long long>(DifferingTexels(reference, maps)));
      }
      std::fflush(stdout);
    }
    std::printf("\n");
  }
  const double base = Median(cpu[0]);
  std::printf("median: one map per draw %.2f CPU-s", base);
  for (size_t c = 1; c < configs.size(); ++c) {
    std::printf("; %d per draw %.2f CPU-s (%.2fx)", configs[c], Median(cpu[c]),
                Median(cpu[c]) / base);
  }
  std::printf("\n");
  return 0;
}

}  // namespace
}  // namespace pdsm

int main(int argc, char** argv) { return pdsm::Run(argc, argv); }
