#include "client/export/attenuation_image.h"

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfStandardAttributes.h>
#include <OpenEXR/ImfStringAttribute.h>
#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <memory>

#include "absl/strings/ascii.h"
#include "absl/strings/str_cat.h"
#include "core/pdsm/exr_output_stream.h"
#include "core/pdsm/refined_pixel.h"
#include "core/reference/embree_handles.h"
#include "core/util/atomic_file.h"
#include "core/util/png_writer.h"

namespace pdsm {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// The image pixel (column, row from the top) of PDSM pixel (x, y): the light view's flip.
size_t ImageIndex(const PdsmGeometry& g, int x, int y) {
  return static_cast<size_t>(g.height - 1 - y) * g.width + (g.width - 1 - x);
}

AttenuationImage EmptyImage(const PdsmGeometry& g) {
  AttenuationImage image;
  image.width = g.width;
  image.height = g.height;
  const size_t pixels = static_cast<size_t>(g.width) * g.height;
  image.attenuation.assign(pixels, kNaN);
  image.depth.assign(pixels, kNaN);
  return image;
}

// The pixel's value at its centre at depth z (a refined pixel's central sub-pixels); NaN nearer
// than what the file resolves.
float EvaluateAt(const PdsmImage& pdsm, int x, int y, double z) {
  if (z < pdsm.header.geometry.z_valid_min) return kNaN;
  return static_cast<float>(EvaluatePixelCentre(pdsm.Function(x, y), z));
}

// Receiver triangles in light space (the file's frame), in double, less `origin`.
struct Receivers {
  std::vector<glm::dvec3> vertices;  // 3 per triangle
  glm::dvec3 origin{0.0};
  double z_min = 0;  // nearest receiver depth, rebased
};

absl::StatusOr<Receivers> GatherReceivers(const Scene& scene, const PdsmGeometry& g) {
  Receivers out;
  glm::dvec3 lo(std::numeric_limits<double>::infinity()), hi(-lo);
  for (const TriangleMesh& mesh : scene.meshes) {
    if (!Receives(mesh.role)) continue;
    for (uint32_t index : mesh.indices) {
      if (index >= mesh.positions_world.size()) {
        return absl::InvalidArgumentError(absl::StrCat(mesh.label, ": index ", index,
                                                       " out of range (",
                                                       mesh.positions_world.size(), " vertices)"));
      }
      const glm::dvec3 v = g.frame.LightFromWorld(mesh.positions_world[index]);
      lo = glm::min(lo, v);
      hi = glm::max(hi, v);
      out.vertices.push_back(v);
    }
    out.vertices.resize(out.vertices.size() / 3 * 3);
  }
  if (out.vertices.empty()) return out;
  // Perspective rays start at the light's centre, the frame's origin. Orthographic ones start
  // anywhere: rebase on the receivers so that floats keep their digits.
  if (g.projection == Projection::kOrthographic) out.origin = 0.5 * (lo + hi);
  for (glm::dvec3& v : out.vertices) v -= out.origin;
  out.z_min = lo.z - out.origin.z;
  return out;
}

absl::StatusOr<EmbreeScene> BuildScene(RTCDevice device, const Receivers& receivers) {
  EmbreeScene scene(rtcNewScene(device));
  rtcSetSceneFlags(scene.get(), RTC_SCENE_FLAG_ROBUST);
  const size_t triangles = receivers.vertices.size() / 3;
  RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
  auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0,
                                                               RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                                               receivers.vertices.size()));
  auto* indices = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
      geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), triangles));
  if (vertices == nullptr || indices == nullptr) {
    rtcReleaseGeometry(geometry);
    return absl::InternalError("embree: cannot allocate the receiver buffers");
  }
  for (size_t k = 0; k < receivers.vertices.size(); ++k) {
    for (int c = 0; c < 3; ++c) vertices[3 * k + c] = static_cast<float>(receivers.vertices[k][c]);
    indices[k] = static_cast<unsigned>(k);
  }
  rtcCommitGeometry(geometry);
  rtcAttachGeometry(scene.get(), geometry);
  rtcReleaseGeometry(geometry);
  rtcCommitScene(scene.get());
  if (rtcGetDeviceError(device) != RTC_ERROR_NONE) {
    return absl::InternalError("embree: building the receiver scene failed");
  }
  return scene;
}

// Depth along the ray `origin + z_step * z` (rebased light space; the ray's z component is
// 1 per unit of depth) where it crosses the plane of triangle `prim`, in double.
double DepthOnTriangle(const Receivers& r, unsigned prim, const glm::dvec3& origin,
                       const glm::dvec3& step) {
  const glm::dvec3& a = r.vertices[3 * prim];
  const glm::dvec3 normal = glm::cross(r.vertices[3 * prim + 1] - a, r.vertices[3 * prim + 2] - a);
  const double denominator = glm::dot(normal, step);
  if (denominator == 0.0) return std::numeric_limits<double>::quiet_NaN();
  return glm::dot(normal, a - origin) / denominator;
}

absl::Status WriteExr(const AttenuationImage& image, const std::string& what,
                      const std::string& path, FileSystem* fs) {
  const size_t pixels = image.attenuation.size();
  std::vector<float> visibility(pixels), alpha(pixels);
  for (size_t p = 0; p < pixels; ++p) {
    const bool defined = !std::isnan(image.attenuation[p]);
    visibility[p] = defined ? 1.0f - image.attenuation[p] : 0.0f;
    alpha[p] = defined ? 1.0f : 0.0f;
  }
  Imf::Header header(image.width, image.height);
  header.compression() = Imf::ZIP_COMPRESSION;
  for (const char* channel : {"A", "Y", "attenuation", "depth"}) {
    header.channels().insert(channel, Imf::Channel(Imf::FLOAT));
  }
  header.insert("pdsmExport", Imf::StringAttribute(what));
  absl::StatusOr<std::unique_ptr<AtomicFile>> file = AtomicFile::Create(path, fs);
  if (!file.ok()) return file.status();
  {
    ExrOutputStream stream(file->get());
    try {
      Imf::OutputFile out(stream, header);
      Imf::FrameBuffer frame;
      const size_t x_stride = sizeof(float), y_stride = sizeof(float) * image.width;
      const auto slice = [&](const float* data) {
        return Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(const_cast<float*>(data)), x_stride,
                          y_stride);
      };
      frame.insert("A", slice(alpha.data()));
      frame.insert("Y", slice(visibility.data()));
      frame.insert("attenuation", slice(image.attenuation.data()));
      frame.insert("depth", slice(image.depth.data()));
      out.setFrameBuffer(frame);
      out.writePixels(image.height);
    } catch (const std::exception& e) {
      if (!stream.error().ok()) return stream.error();
      return absl::InternalError(absl::StrCat(path, ": OpenEXR: ", e.what()));
    }
    if (!stream.error().ok()) return stream.error();
  }
  return (*file)->Commit();
}

absl::Status WritePng(const AttenuationImage& image, const std::string& path, FileSystem* fs) {
  std::vector<uint8_t> gray_alpha(image.attenuation.size() * 2, 0);
  for (size_t p = 0; p < image.attenuation.size(); ++p) {
    const float a = image.attenuation[p];
    if (std::isnan(a)) continue;
    gray_alpha[2 * p] = static_cast<uint8_t>(std::lround(255.0 * std::clamp(1.0 - a, 0.0, 1.0)));
    gray_alpha[2 * p + 1] = 255;
  }
  return WriteGrayAlphaPng(path, image.width, image.height, gray_alpha, fs);
}

}  // namespace

absl::StatusOr<AttenuationImage> AttenuationOnPlane(const PdsmImage& pdsm, double z) {
  if (!std::isfinite(z)) {
    return absl::InvalidArgumentError(absl::StrCat("depth: must be finite (got ", z, ")"));
  }
  const PdsmGeometry& g = pdsm.header.geometry;
  AttenuationImage image = EmptyImage(g);
  // A perspective ray has no point at or behind the light plane.
  if (g.projection == Projection::kPerspective && !(z > 0)) return image;
  for (int y = 0; y < g.height; ++y) {
    for (int x = 0; x < g.width; ++x) {
      const size_t p = ImageIndex(g, x, y);
      image.attenuation[p] = EvaluateAt(pdsm, x, y, z);
      image.depth[p] = static_cast<float>(z);
    }
  }
  return image;
}

absl::StatusOr<AttenuationImage> AttenuationOnReceivers(const PdsmImage& pdsm, const Scene& scene) {
  const PdsmGeometry& g = pdsm.header.geometry;
  AttenuationImage image = EmptyImage(g);
  absl::StatusOr<Receivers> receivers = GatherReceivers(scene, g);
  if (!receivers.ok()) return receivers.status();
  if (receivers->vertices.empty()) return image;
  EmbreeDevice device(rtcNewDevice(nullptr));
  if (device == nullptr) return absl::InternalError("embree: cannot create a device");
  absl::StatusOr<EmbreeScene> rtc_scene = BuildScene(device.get(), *receivers);
  if (!rtc_scene.ok()) return rtc_scene.status();
  const bool ortho = g.projection == Projection::kOrthographic;
  // Orthographic rays start a unit before the nearest receiver; perspective ones at the light.
  const double z_start = ortho ? receivers->z_min - 1.0 : 0.0;
  for (int y = 0; y < g.height; ++y) {
    for (int x = 0; x < g.width; ++x) {
      const double s = g.PixelCenterS(x), t = g.PixelCenterT(y);
      const glm::dvec3 origin =
          ortho ? glm::dvec3(s, t, z_start) - receivers->origin : glm::dvec3(0.0);
      const glm::dvec3 step = ortho ? glm::dvec3(0, 0, 1) : glm::dvec3(s, t, 1);
      RTCIntersectContext context;
      rtcInitIntersectContext(&context);
      RTCRayHit hit{};
      hit.ray.org_x = static_cast<float>(origin.x);
      hit.ray.org_y = static_cast<float>(origin.y);
      hit.ray.org_z = static_cast<float>(origin.z);
      hit.ray.dir_x = static_cast<float>(step.x);
      hit.ray.dir_y = static_cast<float>(step.y);
      hit.ray.dir_z = static_cast<float>(step.z);
      hit.ray.tnear = 0.0f;
      hit.ray.tfar = std::numeric_limits<float>::infinity();
      hit.ray.mask = ~0u;
      hit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
      rtcIntersect1(rtc_scene->get(), &context, &hit);
      if (hit.hit.geomID == RTC_INVALID_GEOMETRY_ID) continue;
      // Light-space depth of the hit: the ray's z is z_start + parameter (its z step is 1).
      const double along = DepthOnTriangle(*receivers, hit.hit.primID, origin, step);
      if (!std::isfinite(along)) continue;
      const double z = ortho ? z_start + along : along;
      const size_t p = ImageIndex(g, x, y);
      image.attenuation[p] = EvaluateAt(pdsm, x, y, z);
      image.depth[p] = static_cast<float>(z);
    }
  }
  return image;
}

absl::Status WriteAttenuationImage(const AttenuationImage& image, const std::string& what,
                                   const std::string& path, FileSystem* fs) {
  const std::string extension =
      absl::AsciiStrToLower(std::filesystem::path(path).extension().string());
  if (extension == ".exr") return WriteExr(image, what, path, fs);
  if (extension == ".png") return WritePng(image, path, fs);
  return absl::InvalidArgumentError(
      absl::StrCat(path, ": unknown image type \"", extension, "\" (use .exr or .png)"));
}

}  // namespace pdsm
