#include "client/view/frame_renderer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include <glm/gtc/matrix_inverse.hpp>

#include "absl/strings/str_cat.h"
#include "client/view/cpu_attenuation.h"
#include "client/view/tile_requests.h"
#include "client/view/view_shaders.h"  // generated: the embedded GLSL sources
#include "core/sampling/light_samples.h"
#include "gl/gl_program.h"
#include "spdlog/spdlog.h"

namespace pdsm::view {
namespace {

using Clock = std::chrono::steady_clock;

double SecondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// Texture units of shade.frag's samplers, and its SSBO bindings.
constexpr int kUnitCpuAttenuation = 1, kUnitShadowMap = 2, kUnitShadowMaps = 3,
              kUnitDynamicMaps = 4, kUnitShadowmask = 5;
constexpr int kBindingLightSamples = 1, kBindingDynamicSamples = 2, kBindingPdsmParts = 6,
              kBindingPdsmPages = 7;
// The tile pool's buffers (shade.frag's PdsmPool0..3).
constexpr int kBindingPdsmPools[kMaxPoolBuffers] = {0, 3, 4, 5};
constexpr float kBackgroundColour[4] = {0.11f, 0.12f, 0.14f, 1.0f};

struct MeshGpu {
  gl::VertexArray vertex_array;
  gl::Buffer buffer;
  GLsizei vertex_count = 0;
  glm::vec3 albedo{0.8f};
  bool casts = true;
  gl::Buffer uv_buffer;    // shadowmasked receivers: UVs at attribute 2
  gl::Texture shadowmask;  // and their texture of A (R32F)
};

MeshGpu UploadMesh(const gl::GlFunctions& gl, const DrawMesh& mesh, bool casts) {
  std::vector<glm::vec3> interleaved;
  interleaved.reserve(2 * mesh.positions.size());
  for (size_t i = 0; i < mesh.positions.size(); ++i) {
    interleaved.push_back(mesh.positions[i]);
    interleaved.push_back(mesh.normals[i]);
  }
  MeshGpu gpu;
  gpu.vertex_array = gl::MakeVertexArray(gl);
  gpu.buffer = gl::MakeBuffer(gl);
  gpu.vertex_count = static_cast<GLsizei>(mesh.positions.size());
  gpu.albedo = mesh.albedo;
  gpu.casts = casts;
  gl.BindVertexArray(gpu.vertex_array.name());
  gl.BindBuffer(GL_ARRAY_BUFFER, gpu.buffer.name());
  gl.BufferData(GL_ARRAY_BUFFER, interleaved.size() * sizeof(glm::vec3), interleaved.data(),
                GL_STATIC_DRAW);
  const GLsizei stride = 2 * sizeof(glm::vec3);
  gl.EnableVertexAttribArray(0);
  gl.VertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, stride, nullptr);
  gl.EnableVertexAttribArray(1);
  gl.VertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, stride,
                         reinterpret_cast<const void*>(sizeof(glm::vec3)));
  gl.BindVertexArray(0);
  return gpu;
}

// A receiver with its shadowmask texture, drawn over its baked mesh in shadowmask mode.
MeshGpu UploadShadowmasked(const gl::GlFunctions& gl, const ShadowmaskedMesh& textured) {
  MeshGpu gpu = UploadMesh(gl, textured.mesh, /*casts=*/false);
  gpu.uv_buffer = gl::MakeBuffer(gl);
  gl.BindVertexArray(gpu.vertex_array.name());
  gl.BindBuffer(GL_ARRAY_BUFFER, gpu.uv_buffer.name());
  gl.BufferData(GL_ARRAY_BUFFER, textured.uvs.size() * sizeof(glm::vec2), textured.uvs.data(),
                GL_STATIC_DRAW);
  gl.EnableVertexAttribArray(2);
  gl.VertexAttribPointer(2, 2, GL_FLOAT, GL_FALSE, sizeof(glm::vec2), nullptr);
  gl.BindVertexArray(0);
  // Bilinear and clamped, as an engine samples a lightmap; row 0 (the image's top) at v = 0,
  // the UVs' convention, so the rows go up as they are.
  gpu.shadowmask = gl::MakeTexture(gl);
  gl.BindTexture(GL_TEXTURE_2D, gpu.shadowmask.name());
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  gl.PixelStorei(GL_UNPACK_ALIGNMENT, 4);
  gl.TexImage2D(GL_TEXTURE_2D, 0, GL_R32F, textured.width, textured.height, 0, GL_RED, GL_FLOAT,
                textured.attenuation.data());
  gl.BindTexture(GL_TEXTURE_2D, 0);
  return gpu;
}

gl::Texture MakeTarget(const gl::GlFunctions& gl, GLint internal_format, GLenum format, GLenum type,
                       int width, int height) {
  gl::Texture texture = gl::MakeTexture(gl);
  gl.BindTexture(GL_TEXTURE_2D, texture.name());
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  gl.TexImage2D(GL_TEXTURE_2D, 0, internal_format, width, height, 0, format, type, nullptr);
  return texture;
}

// The bake's light, for GenerateLightSamples: the header holds everything it reads.
LightSpec LightFromHeader(const PdsmHeader& h) {
  LightSpec light;
  light.shape = h.light_shape;
  light.frame = h.geometry.frame;
  light.half_width = h.light_half_width;
  light.half_height = h.light_half_height;
  light.radius = h.light_radius;
  light.tan_half_angle = h.tan_half_angle;
  return light;
}

// shade.frag's PdsmPart, std430: a mat4 and four 16-byte vectors.
struct PdsmPartGpu {
  glm::mat4 light_from_view;
  glm::vec4 window;
  glm::ivec4 size;
  glm::ivec4 info;
  glm::vec4 extra;
};
static_assert(sizeof(PdsmPartGpu) == 128, "std430 layout of shade.frag's PdsmPart");

// Part i's light space from the view's (part 0's), in double; part 0's is the identity itself,
// so that one light is shaded exactly as before there were several.
std::vector<glm::dmat4> LightFromView(const std::vector<ViewPdsmPart>& parts) {
  const glm::dmat4 world_from_view =
      glm::inverse(LightFromWorldMatrix(parts.front().tiles->header().geometry.frame));
  std::vector<glm::dmat4> out = {glm::dmat4(1.0)};
  for (size_t i = 1; i < parts.size(); ++i) {
    out.push_back(LightFromWorldMatrix(parts[i].tiles->header().geometry.frame) * world_from_view);
  }
  return out;
}

// The parts a frame shades, as shade.frag reads them (the matrices rounded once to float).
std::vector<PdsmPartGpu> PartsForShader(const std::vector<ViewPdsmPart>& parts,
                                        const std::vector<glm::dmat4>& light_from_view,
                                        const PdsmTilePool& pool) {
  std::vector<PdsmPartGpu> out;
  for (size_t i = 0; i < parts.size(); ++i) {
    const PdsmHeader& h = parts[i].tiles->header();
    const PdsmGeometry& g = h.geometry;
    PdsmPartGpu part;
    part.light_from_view = glm::mat4(light_from_view[i]);
    part.window = glm::vec4(glm::vec2(g.s_min, g.t_min),
                            glm::vec2(1.0 / g.PixelPitchS(), 1.0 / g.PixelPitchT()));
    part.size = glm::ivec4(g.width, g.height, h.tile_size,
                           static_cast<int>(pool.page_base(static_cast<int>(i))));
    part.info = glm::ivec4(parts[i].tiles->tiles_x(), g.projection == Projection::kOrthographic,
                           parts[i].group_end, h.face_tangent > 0 ? 1 : 0);
    part.extra = glm::vec4(static_cast<float>(g.z_valid_min), 0.0f, 0.0f, 0.0f);
    out.push_back(part);
  }
  return out;
}

gl::Buffer UploadSamples(const gl::GlFunctions& gl, const std::vector<glm::dvec2>& samples) {
  std::vector<glm::vec2> samples_f(samples.begin(), samples.end());
  if (samples_f.empty()) samples_f.emplace_back(0.0f);
  gl::Buffer buffer = gl::MakeBuffer(gl);
  gl.BindBuffer(GL_SHADER_STORAGE_BUFFER, buffer.name());
  gl.BufferData(GL_SHADER_STORAGE_BUFFER, samples_f.size() * sizeof(glm::vec2), samples_f.data(),
                GL_STATIC_DRAW);
  gl.BindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
  return buffer;
}

}  // namespace

struct FrameRenderer::Impl {
  explicit Impl(const gl::GlFunctions& gl) : shadow_maps(gl), dynamic_maps(gl) {}
  gl::Program shade, shade_every_light, gbuffer, depth;
  std::unique_ptr<PdsmTilePool> pdsm;
  gl::Buffer pdsm_parts;                    // SSBO of PdsmPartGpu
  std::vector<ViewPdsmPart> parts;          // the scene's, as the pool was made
  std::vector<glm::dmat4> light_from_view;  // per part
  std::vector<MeshGpu> baked;
  std::vector<MeshGpu> dynamic;       // parallel to ViewScene::dynamic_objects
  std::vector<MeshGpu> shadowmasked;  // parallel to ViewScene::shadowmasked
  gl::Buffer samples;                 // SSBO of vec2, multi-sm
  gl::Buffer dynamic_samples;         // SSBO of vec2, the dynamic objects' maps
  ShadowMapTargets shadow_maps;
  ShadowMapTargets dynamic_maps;  // layers of the dynamic objects alone (pdsm, cpu)
  ShadowMapLayout single_layout, multi_layout, dynamic_layout;
  gl::Framebuffer target, gbuffer_target;
  gl::Texture colour, attenuation, depth_buffer, positions, cpu_attenuation;
  int width = 0, height = 0;
};

FrameRenderer::FrameRenderer(const gl::GlFunctions& gl, const ViewScene* scene,
                             const RenderSettings& settings)
    : gl_(gl), scene_(scene), settings_(settings), impl_(std::make_unique<Impl>(gl)) {}

FrameRenderer::~FrameRenderer() = default;

absl::StatusOr<std::unique_ptr<FrameRenderer>> FrameRenderer::Create(
    const gl::GlFunctions& gl, const ViewScene* scene, const RenderSettings& settings) {
  GLint major = 0, minor = 0;
  gl.GetIntegerv(GL_MAJOR_VERSION, &major);
  gl.GetIntegerv(GL_MINOR_VERSION, &minor);
  // 4.3 for the shader storage buffer of PDSM vertices, 4.5 for glClipControl (reversed depth).
  if (major < 4 || (major == 4 && minor < 5)) {
    return absl::UnavailableError(absl::StrCat(
        "pdsm-view needs OpenGL 4.5 core (storage buffers, glClipControl); this context is ", major,
        ".", minor));
  }
  std::unique_ptr<FrameRenderer> renderer(new FrameRenderer(gl, scene, settings));
  if (absl::Status s = renderer->Init(); !s.ok()) return s;
  GLint max_block = 0;
  gl.GetIntegerv(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, &max_block);
  spdlog::debug("GL {}.{} ({}), largest PDSM tile pool {} bytes", major, minor,
                reinterpret_cast<const char*>(gl.GetString(GL_RENDERER)), max_block);
  return renderer;
}

absl::Status FrameRenderer::Init() {
  Impl& im = *impl_;
  absl::StatusOr<gl::Program> shade =
      gl::BuildProgram(gl_, kSceneVertexShader, kShadeFragmentShader, "shade");
  if (!shade.ok()) return shade.status();
  im.shade = *std::move(shade);
  // Every light at once is a variant of its own: on llvmpipe the loop over the lights, even
  // behind a uniform branch never taken, made every mode's frame ~1.4x slower.
  std::string every_light(kShadeFragmentShader);
  every_light.insert(every_light.find('\n') + 1, "#define PDSM_EVERY_LIGHT 1\n");
  absl::StatusOr<gl::Program> shade_every_light =
      gl::BuildProgram(gl_, kSceneVertexShader, every_light.c_str(), "shade (every light)");
  if (!shade_every_light.ok()) return shade_every_light.status();
  im.shade_every_light = *std::move(shade_every_light);
  absl::StatusOr<gl::Program> gbuffer =
      gl::BuildProgram(gl_, kSceneVertexShader, kGbufferFragmentShader, "gbuffer");
  if (!gbuffer.ok()) return gbuffer.status();
  im.gbuffer = *std::move(gbuffer);
  absl::StatusOr<gl::Program> depth =
      gl::BuildProgram(gl_, kSceneVertexShader, kShadowDepthFragmentShader, "shadow_depth");
  if (!depth.ok()) return depth.status();
  im.depth = *std::move(depth);

  if (absl::Status s = ReplacePdsm(); !s.ok()) return s;
  for (size_t m = 0; m < scene_->baked.size(); ++m) {
    im.baked.push_back(UploadMesh(gl_, scene_->baked[m], Casts(scene_->scene.meshes[m].role)));
  }
  for (const DynamicObject& object : scene_->dynamic_objects) {
    im.dynamic.push_back(UploadMesh(gl_, object.mesh, true));
  }
  for (const ShadowmaskedMesh& textured : scene_->shadowmasked) {
    im.shadowmasked.push_back(UploadShadowmasked(gl_, textured));
    // The colour of the entry's receiving part (a file whose nodes set roles bakes as several).
    for (size_t m = 0; m < im.baked.size(); ++m) {
      const TriangleMesh& baked = scene_->scene.meshes[m];
      if (baked.entry == textured.mesh_entry && Receives(baked.role)) {
        im.shadowmasked.back().albedo = im.baked[m].albedo;
        break;
      }
    }
  }

  const PdsmHeader& header = scene_->pdsm->header();
  const int sm_size = settings_.sm_size > 0 ? settings_.sm_size : header.shadow_map_resolution;
  const int multi_size = settings_.multi_sm_size > 0 ? settings_.multi_sm_size
                                                     : std::min(header.shadow_map_resolution, 1024);
  im.single_layout = MakeShadowMapLayout(header, sm_size, /*grow_for_samples=*/false);
  im.multi_layout = MakeShadowMapLayout(header, multi_size, /*grow_for_samples=*/true);
  const int count = settings_.sm_count > 0 ? settings_.sm_count : header.samples;
  samples_ = GenerateLightSamples(LightFromHeader(header), count, header.sampling, header.seed);
  im.samples = UploadSamples(gl_, samples_);
  // The dynamic objects' own soft shadow: a few maps from well-spread samples (Sobol) that
  // cover what a sample at the light's edge shifts a receiver, like multi-sm's.
  im.dynamic_layout = MakeShadowMapLayout(header, std::max(settings_.dynamic_sm_size, 1),
                                          /*grow_for_samples=*/true);
  if (!scene_->dynamic_objects.empty() && settings_.dynamic_shadows) {
    dynamic_samples_ =
        GenerateLightSamples(LightFromHeader(header), std::max(settings_.dynamic_sm_count, 1),
                             SamplingPattern::kSobol, header.seed);
  }
  im.dynamic_samples = UploadSamples(gl_, dynamic_samples_);
  dynamic_sample_min_ = glm::dvec2(std::numeric_limits<double>::infinity());
  dynamic_sample_max_ = -dynamic_sample_min_;
  for (const glm::dvec2& a : dynamic_samples_) {
    dynamic_sample_min_ = glm::min(dynamic_sample_min_, a);
    dynamic_sample_max_ = glm::max(dynamic_sample_max_, a);
  }

  for (const gl::Program* program : {&im.shade, &im.shade_every_light}) {
    gl_.UseProgram(program->name());
    const gl::UniformSetter u(gl_, program->name());
    u.Int("cpu_attenuation", kUnitCpuAttenuation);
    u.Int("shadow_map", kUnitShadowMap);
    u.Int("shadow_maps", kUnitShadowMaps);
    u.Int("dynamic_maps", kUnitDynamicMaps);
    u.Int("shadowmask", kUnitShadowmask);
  }
  gl_.UseProgram(0);
  return gl::CheckGlError(gl_, "uploading the scene");
}

const TilePoolStats& FrameRenderer::pdsm_pool_stats() const { return impl_->pdsm->stats(); }

absl::Status FrameRenderer::ReplacePdsm() {
  Impl& im = *impl_;
  im.parts = scene_->Parts();
  im.light_from_view = LightFromView(im.parts);
  std::vector<std::shared_ptr<PdsmTiles>> sources;
  for (const ViewPdsmPart& part : im.parts) sources.push_back(part.tiles);
  absl::StatusOr<std::unique_ptr<PdsmTilePool>> pool = PdsmTilePool::Create(
      gl_, std::move(sources), settings_.gpu_budget_bytes, settings_.max_pool_buffer_bytes);
  if (!pool.ok()) return pool.status();
  im.pdsm = *std::move(pool);
  const std::vector<PdsmPartGpu> for_shader =
      PartsForShader(im.parts, im.light_from_view, *im.pdsm);
  im.pdsm_parts = gl::MakeBuffer(gl_);
  gl_.BindBuffer(GL_SHADER_STORAGE_BUFFER, im.pdsm_parts.name());
  gl_.BufferData(GL_SHADER_STORAGE_BUFFER,
                 static_cast<GLsizeiptr>(for_shader.size() * sizeof(PdsmPartGpu)),
                 for_shader.data(), GL_STATIC_DRAW);
  gl_.BindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
  streamed_valid_ = false;
  return gl::CheckGlError(gl_, "uploading the PDSM's parts");
}

absl::Status FrameRenderer::StreamTiles(const glm::mat4& clip_from_light) {
  Impl& im = *impl_;
  if (streamed_valid_ && clip_from_light == streamed_clip_ && im.width == streamed_width_ &&
      im.height == streamed_height_) {
    return absl::OkStatus();  // the same view of the same scene reads the same tiles
  }
  const auto start = Clock::now();
  std::vector<float> gbuffer;
  if (absl::Status s = RenderGbuffer(clip_from_light, &gbuffer); !s.ok()) return s;
  std::vector<TileRequest> requests = TilesSeen(im.parts[0].tiles->header(), gbuffer);
  for (size_t i = 1; i < im.parts.size(); ++i) {
    std::vector<TileRequest> more = TilesSeen(im.parts[i].tiles->header(), gbuffer,
                                              static_cast<int>(i), &im.light_from_view[i]);
    requests.insert(requests.end(), more.begin(), more.end());
  }
  if (absl::Status s = im.pdsm->Request(std::move(requests)); !s.ok()) return s;
  streamed_valid_ = true;
  streamed_clip_ = clip_from_light;
  streamed_width_ = im.width;
  streamed_height_ = im.height;
  timings_.stream_seconds = SecondsSince(start);
  return absl::OkStatus();
}
uint64_t FrameRenderer::shadow_map_bytes() const {
  return impl_->shadow_maps.bytes() + impl_->dynamic_maps.bytes();
}

absl::Status FrameRenderer::EnsureTarget(int width, int height) {
  Impl& im = *impl_;
  if (width == im.width && height == im.height) return absl::OkStatus();
  im.colour = MakeTarget(gl_, GL_RGBA8, GL_RGBA, GL_UNSIGNED_BYTE, width, height);
  im.attenuation = MakeTarget(gl_, GL_R32F, GL_RED, GL_FLOAT, width, height);
  im.depth_buffer =
      MakeTarget(gl_, GL_DEPTH_COMPONENT32F, GL_DEPTH_COMPONENT, GL_FLOAT, width, height);
  im.positions = MakeTarget(gl_, GL_RGBA32F, GL_RGBA, GL_FLOAT, width, height);
  im.cpu_attenuation = MakeTarget(gl_, GL_R32F, GL_RED, GL_FLOAT, width, height);
  if (!im.target) im.target = gl::MakeFramebuffer(gl_);
  if (!im.gbuffer_target) im.gbuffer_target = gl::MakeFramebuffer(gl_);
  const auto check = [&](const char* what) -> absl::Status {
    const GLenum status = gl_.CheckFramebufferStatus(GL_FRAMEBUFFER);
    if (status != GL_FRAMEBUFFER_COMPLETE) {
      return absl::InternalError(absl::StrCat(what, " framebuffer incomplete: ", status));
    }
    return absl::OkStatus();
  };
  gl_.BindFramebuffer(GL_FRAMEBUFFER, im.target.name());
  gl_.FramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, im.colour.name(),
                           0);
  gl_.FramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT1, GL_TEXTURE_2D,
                           im.attenuation.name(), 0);
  gl_.FramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D,
                           im.depth_buffer.name(), 0);
  const GLenum buffers[2] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
  gl_.DrawBuffers(2, buffers);
  if (absl::Status s = check("frame"); !s.ok()) return s;
  gl_.BindFramebuffer(GL_FRAMEBUFFER, im.gbuffer_target.name());
  gl_.FramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, im.positions.name(),
                           0);
  gl_.FramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D,
                           im.depth_buffer.name(), 0);
  gl_.DrawBuffers(1, buffers);
  if (absl::Status s = check("G-buffer"); !s.ok()) return s;
  im.width = width;
  im.height = height;
  return gl::CheckGlError(gl_, absl::StrCat("allocating a ", width, "x", height, " frame"));
}

void FrameRenderer::DrawScene(const gl::UniformSetter& u, DrawSet set) const {
  const Impl& im = *impl_;
  const auto draw = [&](const MeshGpu& mesh, const glm::dmat4& light_from_object) {
    u.Mat4("light_from_object", glm::mat4(light_from_object));
    u.Mat3("normal_from_object", glm::mat3(glm::inverseTranspose(glm::dmat3(light_from_object))));
    u.Vec3("albedo", mesh.albedo);
    gl_.BindVertexArray(mesh.vertex_array.name());
    gl_.DrawArrays(GL_TRIANGLES, 0, mesh.vertex_count);
  };
  for (const MeshGpu& mesh : im.baked) {
    if (set == DrawSet::kAll || (set == DrawSet::kCasters && mesh.casts)) {
      draw(mesh, glm::dmat4(1.0));
    }
  }
  // Dynamic objects were not in the bake: they receive the PDSM's shadow and cast, into the
  // shadow-map modes' maps and into maps of their own for the PDSM modes.
  const glm::dmat4 light_from_world = scene_->LightFromWorld();
  for (size_t i = 0; i < im.dynamic.size(); ++i) {
    draw(im.dynamic[i], light_from_world * scene_->dynamic_objects[i].world_from_object);
  }
  gl_.BindVertexArray(0);
}

void FrameRenderer::DrawShadowmasked(const gl::UniformSetter& u) const {
  const Impl& im = *impl_;
  if (im.shadowmasked.empty()) return;
  // Each textured receiver is part of a baked mesh again (the same triangles and transforms,
  // composed in double here and by the mesh import in float: equal within rounding). Drawn
  // second, pulled a few depth steps towards the eye, it wins the depth test over its own
  // baked copy and stays behind whatever was in front of it.
  gl_.Enable(GL_POLYGON_OFFSET_FILL);
  gl_.PolygonOffset(-1.0f, -4.0f);
  gl_.DepthFunc(GL_LEQUAL);
  u.Int("shadowmask_textured", 1);
  u.Mat4("light_from_object", glm::mat4(1.0f));
  u.Mat3("normal_from_object", glm::mat3(1.0f));
  gl_.ActiveTexture(GL_TEXTURE0 + kUnitShadowmask);
  for (const MeshGpu& mesh : im.shadowmasked) {
    gl_.BindTexture(GL_TEXTURE_2D, mesh.shadowmask.name());
    u.Vec3("albedo", mesh.albedo);
    gl_.BindVertexArray(mesh.vertex_array.name());
    gl_.DrawArrays(GL_TRIANGLES, 0, mesh.vertex_count);
  }
  gl_.BindVertexArray(0);
  gl_.ActiveTexture(GL_TEXTURE0);
  u.Int("shadowmask_textured", 0);
  gl_.DepthFunc(GL_LESS);
  gl_.PolygonOffset(0.0f, 0.0f);
  gl_.Disable(GL_POLYGON_OFFSET_FILL);
}

void FrameRenderer::SetDepthUniforms(const gl::UniformSetter& u) const {
  const PdsmHeader& header = scene_->pdsm->header();
  u.Float("depth_bias", static_cast<float>(header.depth_bias));
  u.Float("slope_bias", static_cast<float>(header.slope_bias));
  // The bake widens the slope bias to a PDSM pixel (footprint_scale = PDSM pixel / texel)
  // because its bilinear lookup reads neighbouring rays, up to a pixel away. These maps are
  // looked up where the receiver itself projects into them, within a texel of their own
  // lattice (PCF/PCSS/VSM filter around that point with their own kernels), so one texel is
  // the step to cover: 1, and the comparison modes keep the bias a plain shadow map has.
  u.Float("footprint_scale", 1.0f);
  u.Float("z_near", static_cast<float>(header.geometry.z_near));
  u.Float("z_far", static_cast<float>(header.geometry.z_far));
  const ShadowClipRange clip = ShadowClipRangeOf(header.geometry);
  u.Float("clip_near", static_cast<float>(clip.near));
  u.Float("clip_far", static_cast<float>(clip.far));
  u.Int("orthographic", header.geometry.projection == Projection::kOrthographic);
}

void FrameRenderer::UpdateDynamicReach() {
  const PdsmGeometry& g = scene_->pdsm->header().geometry;
  const bool orthographic = g.projection == Projection::kOrthographic;
  const glm::dmat4 light_from_world = scene_->LightFromWorld();
  glm::dvec2 lo(std::numeric_limits<double>::infinity()), hi(-lo);
  dynamic_reach_bounded_ = true;
  for (const DynamicObject& object : scene_->dynamic_objects) {
    // The object's light-space box: (x - a) / z and x - a z take their extremes over a box at
    // its corners, so 8 corners per sample bound the whole projection.
    const glm::dmat4 light_from_object = light_from_world * object.world_from_object;
    glm::dvec3 box_lo(std::numeric_limits<double>::infinity()), box_hi(-box_lo);
    for (const glm::vec3& p : object.mesh.positions) {
      const glm::dvec3 q(light_from_object * glm::dvec4(glm::dvec3(p), 1.0));
      box_lo = glm::min(box_lo, q);
      box_hi = glm::max(box_hi, q);
    }
    if (!orthographic && !(box_lo.z > 0)) {
      dynamic_reach_bounded_ = false;
      return;
    }
    for (int c = 0; c < 8; ++c) {
      const glm::dvec3 q((c & 1) ? box_hi.x : box_lo.x, (c & 2) ? box_hi.y : box_lo.y,
                         (c & 4) ? box_hi.z : box_lo.z);
      for (const glm::dvec2& a : dynamic_samples_) {
        const glm::dvec2 st = orthographic ? glm::dvec2(q) - a * q.z : (glm::dvec2(q) - a) / q.z;
        lo = glm::min(lo, st);
        hi = glm::max(hi, st);
      }
    }
  }
  const glm::dvec2 texel = impl_->dynamic_layout.window_size / double(impl_->dynamic_layout.size);
  dynamic_reach_min_ = lo - texel;
  dynamic_reach_max_ = hi + texel;
}

bool FrameRenderer::CastsDynamicShadows(ViewMode mode) const {
  return (mode == ViewMode::kPdsm || mode == ViewMode::kCpu || mode == ViewMode::kShadowmask) &&
         settings_.dynamic_shadows && !dynamic_samples_.empty();
}

absl::Status FrameRenderer::EnsureDynamicShadowMaps(ViewMode mode) {
  Impl& im = *impl_;
  if (!CastsDynamicShadows(mode) || dynamic_valid_) return absl::OkStatus();
  const auto start = Clock::now();
  UpdateDynamicReach();
  gl_.UseProgram(im.depth.name());
  const gl::UniformSetter u(gl_, im.depth.name());
  SetDepthUniforms(u);
  absl::Status s =
      im.dynamic_maps.RenderLayers(scene_->pdsm->header(), im.dynamic_layout, dynamic_samples_,
                                   [&](const glm::mat4& clip_from_light) {
                                     u.Mat4("clip_from_light", clip_from_light);
                                     DrawScene(u, DrawSet::kDynamic);
                                   });
  if (!s.ok()) return s;
  dynamic_valid_ = true;
  gl_.Finish();
  timings_.shadow_map_seconds += SecondsSince(start);
  return absl::OkStatus();
}

absl::Status FrameRenderer::EnsureShadowMaps(ViewMode mode) {
  Impl& im = *impl_;
  const bool single = UsesShadowMap(mode) && !single_valid_;
  const bool layers = mode == ViewMode::kMultiSm && !layers_valid_;
  if (!single && !layers) return EnsureDynamicShadowMaps(mode);
  const auto start = Clock::now();
  const PdsmHeader& header = scene_->pdsm->header();
  gl_.UseProgram(im.depth.name());
  const gl::UniformSetter u(gl_, im.depth.name());
  SetDepthUniforms(u);
  const auto draw = [&](const glm::mat4& clip_from_light) {
    u.Mat4("clip_from_light", clip_from_light);
    DrawScene(u, DrawSet::kCasters);
  };
  if (single) {
    if (absl::Status s = im.shadow_maps.RenderSingle(header, im.single_layout, draw); !s.ok()) {
      return s;
    }
    single_valid_ = true;
  }
  if (layers) {
    absl::Status s = im.shadow_maps.RenderLayers(header, im.multi_layout, samples_, draw);
    if (!s.ok()) return s;
    layers_valid_ = true;
  }
  gl_.Finish();
  timings_.shadow_map_seconds = SecondsSince(start);
  return absl::OkStatus();
}

absl::Status FrameRenderer::RenderGbuffer(const glm::mat4& clip_from_light,
                                          std::vector<float>* gbuffer) {
  Impl& im = *impl_;
  gl_.BindFramebuffer(GL_FRAMEBUFFER, im.gbuffer_target.name());
  const float no_surface[4] = {0, 0, 0, 0};
  const float far_depth = 1.0f;
  gl_.ClearBufferfv(GL_COLOR, 0, no_surface);
  gl_.ClearBufferfv(GL_DEPTH, 0, &far_depth);
  gl_.UseProgram(im.gbuffer.name());
  const gl::UniformSetter u(gl_, im.gbuffer.name());
  u.Mat4("clip_from_light", clip_from_light);
  DrawScene(u, DrawSet::kAll);
  gbuffer->resize(static_cast<size_t>(im.width) * im.height * 4);
  gl_.ReadBuffer(GL_COLOR_ATTACHMENT0);
  gl_.PixelStorei(GL_PACK_ALIGNMENT, 4);
  gl_.ReadPixels(0, 0, im.width, im.height, GL_RGBA, GL_FLOAT, gbuffer->data());
  return gl::CheckGlError(gl_, "rendering the G-buffer");
}

absl::StatusOr<std::vector<float>> FrameRenderer::ReadPositions(const Camera& camera, int width,
                                                                int height) {
  if (absl::Status s = EnsureTarget(width, height); !s.ok()) return s;
  gl_.Viewport(0, 0, width, height);
  gl_.ClipControl(GL_LOWER_LEFT, GL_NEGATIVE_ONE_TO_ONE);
  gl_.Enable(GL_DEPTH_TEST);
  gl_.DepthFunc(GL_LESS);
  gl_.DepthMask(GL_TRUE);
  gl_.Disable(GL_CULL_FACE);
  std::vector<float> gbuffer;
  if (absl::Status s = RenderGbuffer(
          ClipFromLight(camera, *scene_, static_cast<double>(width) / height), &gbuffer);
      !s.ok()) {
    return s;
  }
  // GL's row 0 is the bottom; images start at the top.
  std::vector<float> out(gbuffer.size());
  const size_t row = static_cast<size_t>(width) * 4;
  for (int y = 0; y < height; ++y) {
    std::copy_n(&gbuffer[static_cast<size_t>(height - 1 - y) * row], row, &out[y * row]);
  }
  return out;
}

absl::Status FrameRenderer::RenderCpuAttenuation(const glm::mat4& clip_from_light) {
  Impl& im = *impl_;
  const auto start = Clock::now();
  std::vector<float> gbuffer;
  if (absl::Status s = RenderGbuffer(clip_from_light, &gbuffer); !s.ok()) return s;
  const absl::StatusOr<std::vector<float>> attenuation =
      EvaluateAttenuationImage(*scene_->pdsm, gbuffer, im.width, im.height, kPending);
  if (!attenuation.ok()) return attenuation.status();
  gl_.BindTexture(GL_TEXTURE_2D, im.cpu_attenuation.name());
  gl_.PixelStorei(GL_UNPACK_ALIGNMENT, 4);
  gl_.TexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, im.width, im.height, GL_RED, GL_FLOAT,
                    attenuation->data());
  timings_.cpu_seconds = SecondsSince(start);
  return gl::CheckGlError(gl_, "evaluating the PDSM on the CPU");
}

void FrameRenderer::SetShadeUniforms(ViewMode mode, const Camera& camera,
                                     const gl::UniformSetter& u) const {
  const Impl& im = *impl_;
  const PdsmHeader& header = scene_->pdsm->header();
  const PdsmGeometry& g = header.geometry;
  u.Int("mode", static_cast<int>(mode));
  u.Vec3("eye_light", glm::vec3(g.frame.LightFromWorld(camera.eye_world)));
  u.Int("orthographic", g.projection == Projection::kOrthographic);
  u.Float("ambient", settings_.ambient);
  u.Int("bilinear", settings_.bilinear ? 1 : 0);
  u.Int("pdsm_part_count", mode == ViewMode::kPdsm && !scene_->every_light.empty()
                               ? static_cast<int>(scene_->every_light.size())
                               : 1);
  const ShadowMapLayout& layout = mode == ViewMode::kMultiSm ? im.multi_layout : im.single_layout;
  u.Vec2("sm_window_min", glm::vec2(layout.window_min));
  u.Vec2("sm_window_size", glm::vec2(layout.window_size));
  u.Int2("sm_size", glm::ivec2(layout.size));
  u.Int("sample_count", static_cast<int>(samples_.size()));
  u.Vec2("light_half_extent", glm::vec2(LightHalfExtent(header)));
  u.Float("z_near", static_cast<float>(g.z_near));
  u.Float("z_far", static_cast<float>(g.z_far));
  u.Int("filter_radius", settings_.filter_radius);
  u.Int("dynamic_count", CastsDynamicShadows(mode) ? static_cast<int>(dynamic_samples_.size()) : 0);
  u.Vec2("dynamic_window_min", glm::vec2(im.dynamic_layout.window_min));
  u.Vec2("dynamic_window_size", glm::vec2(im.dynamic_layout.window_size));
  u.Int2("dynamic_sm_size", glm::ivec2(im.dynamic_layout.size));
  u.Int("dynamic_combine", static_cast<int>(settings_.dynamic_combine));
  u.Int("dynamic_bounded", dynamic_reach_bounded_ ? 1 : 0);
  u.Vec2("dynamic_reach_min", glm::vec2(dynamic_reach_min_));
  u.Vec2("dynamic_reach_max", glm::vec2(dynamic_reach_max_));
  u.Vec2("dynamic_sample_min", glm::vec2(dynamic_sample_min_));
  u.Vec2("dynamic_sample_max", glm::vec2(dynamic_sample_max_));
}

absl::Status FrameRenderer::Render(ViewMode mode, const Camera& camera, int width, int height) {
  Impl& im = *impl_;
  timings_ = FrameTimings{};
  if (absl::Status s = EnsureTarget(width, height); !s.ok()) return s;
  if (absl::Status s = EnsureShadowMaps(mode); !s.ok()) return s;
  const glm::mat4 clip_from_light =
      ClipFromLight(camera, *scene_, static_cast<double>(width) / height);
  gl_.Viewport(0, 0, width, height);
  gl_.ClipControl(GL_LOWER_LEFT, GL_NEGATIVE_ONE_TO_ONE);  // glm::perspective's convention
  gl_.Enable(GL_DEPTH_TEST);
  gl_.DepthFunc(GL_LESS);
  gl_.DepthMask(GL_TRUE);
  gl_.Disable(GL_CULL_FACE);
  gl_.Disable(GL_SCISSOR_TEST);
  if (mode == ViewMode::kCpu) {
    if (absl::Status s = RenderCpuAttenuation(clip_from_light); !s.ok()) return s;
  }
  if (mode == ViewMode::kPdsm || mode == ViewMode::kShadowmask) {
    if (absl::Status s = StreamTiles(clip_from_light); !s.ok()) return s;
  }
  const auto start = Clock::now();
  gl_.BindFramebuffer(GL_FRAMEBUFFER, im.target.name());
  const float no_attenuation[4] = {kBackground, 0, 0, 0};
  const float far_depth = 1.0f;
  gl_.ClearBufferfv(GL_COLOR, 0, kBackgroundColour);
  gl_.ClearBufferfv(GL_COLOR, 1, no_attenuation);
  gl_.ClearBufferfv(GL_DEPTH, 0, &far_depth);
  const bool every_light = mode == ViewMode::kPdsm && !scene_->every_light.empty();
  const GLuint program = every_light ? im.shade_every_light.name() : im.shade.name();
  gl_.UseProgram(program);
  const gl::UniformSetter u(gl_, program);
  u.Mat4("clip_from_light", clip_from_light);
  SetShadeUniforms(mode, camera, u);
  gl_.ActiveTexture(GL_TEXTURE0 + kUnitCpuAttenuation);
  gl_.BindTexture(GL_TEXTURE_2D, im.cpu_attenuation.name());
  gl_.ActiveTexture(GL_TEXTURE0 + kUnitShadowMap);
  gl_.BindTexture(GL_TEXTURE_2D, im.shadow_maps.single());
  gl_.ActiveTexture(GL_TEXTURE0 + kUnitShadowMaps);
  gl_.BindTexture(GL_TEXTURE_2D_ARRAY, im.shadow_maps.layers());
  gl_.ActiveTexture(GL_TEXTURE0 + kUnitDynamicMaps);
  gl_.BindTexture(GL_TEXTURE_2D_ARRAY, im.dynamic_maps.layers());
  gl_.ActiveTexture(GL_TEXTURE0);
  gl_.BindBufferBase(GL_SHADER_STORAGE_BUFFER, kBindingPdsmParts, im.pdsm_parts.name());
  gl_.BindBufferBase(GL_SHADER_STORAGE_BUFFER, kBindingPdsmPages, im.pdsm->page_table());
  for (int i = 0; i < kMaxPoolBuffers; ++i) {
    // A binding no page entry points at still needs a buffer: the first one stands in.
    const GLuint pool = im.pdsm->pool(i) != 0 ? im.pdsm->pool(i) : im.pdsm->pool(0);
    gl_.BindBufferBase(GL_SHADER_STORAGE_BUFFER, kBindingPdsmPools[i], pool);
  }
  gl_.BindBufferBase(GL_SHADER_STORAGE_BUFFER, kBindingLightSamples, im.samples.name());
  gl_.BindBufferBase(GL_SHADER_STORAGE_BUFFER, kBindingDynamicSamples, im.dynamic_samples.name());
  u.Int("shadowmask_textured", 0);
  DrawScene(u, DrawSet::kAll);
  if (mode == ViewMode::kShadowmask) DrawShadowmasked(u);
  gl_.Finish();
  timings_.shade_seconds = SecondsSince(start);
  return gl::CheckGlError(gl_, absl::StrCat("rendering mode ", ModeName(mode)));
}

absl::StatusOr<Frame> FrameRenderer::ReadFrame() {
  Impl& im = *impl_;
  Frame frame;
  frame.width = im.width;
  frame.height = im.height;
  const size_t pixels = static_cast<size_t>(im.width) * im.height;
  std::vector<uint8_t> rgba(pixels * 4);
  std::vector<float> attenuation(pixels);
  gl_.BindFramebuffer(GL_FRAMEBUFFER, im.target.name());
  gl_.PixelStorei(GL_PACK_ALIGNMENT, 1);
  gl_.ReadBuffer(GL_COLOR_ATTACHMENT0);
  gl_.ReadPixels(0, 0, im.width, im.height, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
  gl_.ReadBuffer(GL_COLOR_ATTACHMENT1);
  gl_.ReadPixels(0, 0, im.width, im.height, GL_RED, GL_FLOAT, attenuation.data());
  if (absl::Status s = gl::CheckGlError(gl_, "reading the frame back"); !s.ok()) return s;
  // GL's row 0 is the bottom; images start at the top.
  frame.rgb.resize(pixels * 3);
  frame.attenuation.resize(pixels);
  for (int y = 0; y < im.height; ++y) {
    const size_t src_row = static_cast<size_t>(im.height - 1 - y) * im.width;
    const size_t dst_row = static_cast<size_t>(y) * im.width;
    for (int x = 0; x < im.width; ++x) {
      for (int c = 0; c < 3; ++c) frame.rgb[3 * (dst_row + x) + c] = rgba[4 * (src_row + x) + c];
      frame.attenuation[dst_row + x] = attenuation[src_row + x];
    }
  }
  return frame;
}

void FrameRenderer::BlitToScreen(int screen_width, int screen_height) {
  Impl& im = *impl_;
  gl_.BindFramebuffer(GL_READ_FRAMEBUFFER, im.target.name());
  gl_.ReadBuffer(GL_COLOR_ATTACHMENT0);
  gl_.BindFramebuffer(GL_DRAW_FRAMEBUFFER, 0);
  gl_.BlitFramebuffer(0, 0, im.width, im.height, 0, 0, screen_width, screen_height,
                      GL_COLOR_BUFFER_BIT, GL_NEAREST);
  gl_.BindFramebuffer(GL_FRAMEBUFFER, 0);
}

}  // namespace pdsm::view
