#include "client/view/view_scene.h"

#include <cmath>
#include <limits>
#include <numbers>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "core/scene/mesh_file.h"

namespace pdsm::view {
namespace {

// Distinct, not too saturated colours, so the meshes are told apart in every mode.
constexpr glm::vec3 kPalette[] = {{0.82f, 0.80f, 0.76f}, {0.85f, 0.45f, 0.35f},
                                  {0.40f, 0.62f, 0.85f}, {0.55f, 0.78f, 0.45f},
                                  {0.86f, 0.74f, 0.38f}, {0.68f, 0.52f, 0.80f}};

// Relative tolerance on light parameters read back from the header (doubles round-trip
// through the EXR header exactly, but a scene edited by hand should still pass).
constexpr double kMatchTolerance = 1e-6;

bool Near(double a, double b, double scale) {
  return std::abs(a - b) <= kMatchTolerance * std::max(1.0, scale);
}

bool NearVec(const glm::dvec3& a, const glm::dvec3& b, double scale) {
  return Near(a.x, b.x, scale) && Near(a.y, b.y, scale) && Near(a.z, b.z, scale);
}

std::string Vec(const glm::dvec3& v) { return absl::StrFormat("(%g, %g, %g)", v.x, v.y, v.z); }

void AppendTriangle(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c, DrawMesh* mesh) {
  glm::dvec3 normal = glm::cross(b - a, c - a);
  const double length = glm::length(normal);
  normal = length > 0 ? normal / length : glm::dvec3(0, 0, 1);
  for (const glm::dvec3* p : {&a, &b, &c}) {
    mesh->positions.push_back(glm::vec3(*p));
    mesh->normals.push_back(glm::vec3(normal));
  }
}

}  // namespace

glm::dmat4 LightFromWorldMatrix(const LightFrame& f) {
  // Rows u, v, n; translation -R c. glm is column-major: m[col][row].
  glm::dmat4 m(1.0);
  for (int col = 0; col < 3; ++col) {
    m[col][0] = f.u[col];
    m[col][1] = f.v[col];
    m[col][2] = f.n[col];
  }
  m[3][0] = -glm::dot(f.u, f.center);
  m[3][1] = -glm::dot(f.v, f.center);
  m[3][2] = -glm::dot(f.n, f.center);
  return m;
}

glm::dmat4 ViewScene::LightFromWorld() const { return LightFromWorldMatrix(frame()); }

std::vector<ViewPdsmPart> ViewScene::Parts() const {
  if (!every_light.empty()) return every_light;
  return {ViewPdsmPart{pdsm, 1}};
}

absl::Status CheckPdsmMatchesScene(const Scene& scene, const PdsmHeader& header,
                                   const std::string& pdsm_path) {
  const auto mismatch = [&](const std::string& field, const std::string& detail) {
    return absl::InvalidArgumentError(absl::StrCat(
        pdsm_path, ": header ", field, " does not match ", scene.source_path, ": ", detail,
        " (was this PDSM baked from this scene? --allow-mismatch shows it anyway)"));
  };
  if (header.scene_name != scene.name) {
    return mismatch("scene_name",
                    absl::StrCat("\"", header.scene_name, "\" vs \"", scene.name, "\""));
  }
  const LightSpec& light = scene.light;
  if (header.light_shape != light.shape) {
    return mismatch("light_shape", absl::StrCat(LightShapeName(header.light_shape), " vs ",
                                                LightShapeName(light.shape)));
  }
  const LightFrame& baked = header.geometry.frame;
  if (!NearVec(baked.n, light.frame.n, 1.0)) {
    return mismatch("light normal", Vec(baked.n) + " vs " + Vec(light.frame.n));
  }
  if (light.shape == LightShape::kSun) {
    if (!Near(header.tan_half_angle, light.tan_half_angle, 1.0)) {
      return mismatch("tan_half_angle",
                      absl::StrCat(header.tan_half_angle, " vs ", light.tan_half_angle));
    }
    return absl::OkStatus();
  }
  const double scale = glm::length(light.frame.center);
  if (!NearVec(baked.center, light.frame.center, scale)) {
    return mismatch("light centre", Vec(baked.center) + " vs " + Vec(light.frame.center));
  }
  if (!Near(header.light_half_width, light.half_width, light.half_width) ||
      !Near(header.light_half_height, light.half_height, light.half_height) ||
      !Near(header.light_radius, light.radius, light.radius)) {
    return mismatch("light size",
                    absl::StrCat("half extents ", header.light_half_width, " x ",
                                 header.light_half_height, " r ", header.light_radius, " vs ",
                                 light.half_width, " x ", light.half_height, " r ", light.radius));
  }
  return absl::OkStatus();
}

std::vector<DrawMesh> BuildBakedMeshes(const Scene& scene, const LightFrame& frame) {
  std::vector<DrawMesh> meshes;
  for (size_t m = 0; m < scene.meshes.size(); ++m) {
    const TriangleMesh& source = scene.meshes[m];
    DrawMesh mesh;
    mesh.label = source.label;
    // Receivers alone (ground planes) stay neutral; casters get the colours.
    mesh.albedo = source.role == MeshRole::kReceiverOnly
                      ? kPalette[0]
                      : kPalette[1 + m % (std::size(kPalette) - 1)];
    mesh.positions.reserve(source.indices.size());
    mesh.normals.reserve(source.indices.size());
    for (size_t i = 0; i + 2 < source.indices.size(); i += 3) {
      AppendTriangle(frame.LightFromWorld(source.positions_world[source.indices[i]]),
                     frame.LightFromWorld(source.positions_world[source.indices[i + 1]]),
                     frame.LightFromWorld(source.positions_world[source.indices[i + 2]]), &mesh);
    }
    meshes.push_back(std::move(mesh));
  }
  return meshes;
}

void PrepareViewScene(ViewScene* view) {
  view->baked = BuildBakedMeshes(view->scene, view->frame());
  SceneBounds(view->scene, false, &view->bounds_min_world, &view->bounds_max_world);
  SceneBounds(view->scene, true, &view->casters_min_world, &view->casters_max_world);
}

DrawMesh MakeUnitSphere(int segments, int rings) {
  DrawMesh mesh;
  mesh.label = "sphere";
  mesh.albedo = glm::vec3(0.95f, 0.35f, 0.55f);
  const auto point = [&](int s, int r) {
    const double theta = std::numbers::pi * r / rings;
    const double phi = 2 * std::numbers::pi * s / segments;
    return glm::dvec3(std::sin(theta) * std::cos(phi), std::cos(theta),
                      std::sin(theta) * std::sin(phi));
  };
  for (int r = 0; r < rings; ++r) {
    for (int s = 0; s < segments; ++s) {
      const glm::dvec3 a = point(s, r), b = point(s + 1, r);
      const glm::dvec3 c = point(s + 1, r + 1), d = point(s, r + 1);
      // Smooth normals for a sphere: the position itself.
      for (const glm::dvec3* p : {&a, &b, &c, &a, &c, &d}) {
        mesh.positions.push_back(glm::vec3(*p));
        mesh.normals.push_back(glm::vec3(*p));
      }
    }
  }
  return mesh;
}

absl::StatusOr<DrawMesh> LoadObjectMesh(const std::string& path, const std::string& context) {
  absl::StatusOr<MeshFileData> data = LoadMeshFile(path, context);
  if (!data.ok()) return data.status();
  DrawMesh mesh;
  mesh.label = path;
  mesh.albedo = glm::vec3(0.95f, 0.35f, 0.55f);
  for (size_t i = 0; i + 2 < data->indices.size(); i += 3) {
    AppendTriangle(data->positions[data->indices[i]], data->positions[data->indices[i + 1]],
                   data->positions[data->indices[i + 2]], &mesh);
  }
  return mesh;
}

void SceneBounds(const Scene& scene, bool casters_only, glm::dvec3* min_world,
                 glm::dvec3* max_world) {
  glm::dvec3 lo(std::numeric_limits<double>::infinity());
  glm::dvec3 hi(-std::numeric_limits<double>::infinity());
  for (const TriangleMesh& mesh : scene.meshes) {
    if (casters_only && !Casts(mesh.role)) continue;
    for (const glm::dvec3& p : mesh.positions_world) {
      lo = glm::min(lo, p);
      hi = glm::max(hi, p);
    }
  }
  if (lo.x > hi.x) {
    if (casters_only) return SceneBounds(scene, false, min_world, max_world);
    lo = hi = glm::dvec3(0.0);  // no geometry
  }
  *min_world = lo;
  *max_world = hi;
}

}  // namespace pdsm::view
