// What the viewer draws: the scene file's meshes and the PDSM, both in the PDSM's light
// space, plus dynamic objects that were not in the bake (thesis 4.3).
//
// Every position goes to the GPU relative to the light centre in the light's axes, computed
// in double on the CPU and rounded once to float, so a world 1e6 units from its origin keeps
// its precision (DESIGN.md "Numerical notes").
#ifndef PDSM_CLIENT_VIEW_VIEW_SCENE_H_
#define PDSM_CLIENT_VIEW_VIEW_SCENE_H_

#include <memory>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "client/view/pdsm_tiles.h"
#include "core/bake/bake_plan.h"
#include "core/pdsm/pdsm_image.h"
#include "core/scene/scene.h"

namespace pdsm::view {

// Non-indexed triangles with flat normals (3 vertices per triangle).
struct DrawMesh {
  std::string label;
  std::vector<glm::vec3> positions;
  std::vector<glm::vec3> normals;
  glm::vec3 albedo{0.8f};
};

// A mesh placed by a transform the viewer may change every frame (arrow keys).
struct DynamicObject {
  DrawMesh mesh;  // object space
  glm::dmat4 world_from_object{1.0};
};

// A receiver with its shadowmask texture (`--mode shadowmask`, client/view/shadowmask_textures.h):
// the attenuation A (a `--visibility` file turned back into A = 1 - value), one float a texel,
// row 0 at the top of the image (v = 0).
struct ShadowmaskedMesh {
  DrawMesh mesh;               // light space, flat normals, 3 vertices a triangle
  int mesh_entry = 0;          // the scene's meshes[] entry (whose colour it takes)
  std::vector<glm::vec2> uvs;  // parallel to mesh.positions
  int width = 0, height = 0;
  std::vector<float> attenuation;
};

// One part of a PDSM file shaded together with the others: a light, or one face of a sphere
// light (core/pdsm/pdsm_lights.h).
struct ViewPdsmPart {
  std::shared_ptr<PdsmTiles> tiles;
  int group_end = 0;  // the first part past its light's (a sphere's faces are one light)
};

struct ViewScene {
  Scene scene;
  // The PDSM's tiles, read as frames need them (a file of any size), or a whole map in memory
  // with its pending tiles (--server, a job running).
  std::shared_ptr<PdsmTiles> pdsm;
  // pdsm-view without --light on a scene and file of several lights: every part of the file in
  // file order, shaded together in pdsm mode (every_light[0].tiles is `pdsm`, whose light
  // space is the view's). Empty: `pdsm` alone.
  std::vector<ViewPdsmPart> every_light;
  std::shared_ptr<const BakePlan> plan;  // the scene's plan, when following a running job
  std::vector<DrawMesh> baked;           // light space: the scene file's meshes
  std::vector<DynamicObject> dynamic_objects;
  std::vector<ShadowmaskedMesh> shadowmasked;  // --shadowmask: receivers with their textures
  glm::dvec3 bounds_min_world{0.0};            // of the baked meshes
  glm::dvec3 bounds_max_world{0.0};
  glm::dvec3 casters_min_world{0.0};  // of the casting meshes: what the default camera frames
  glm::dvec3 casters_max_world{0.0};

  const LightFrame& frame() const { return pdsm->header().geometry.frame; }
  // light_from_world as a matrix, and light_from_object for a dynamic object (double).
  glm::dmat4 LightFromWorld() const;
  // The parts a frame shades: every_light, or `pdsm` alone.
  std::vector<ViewPdsmPart> Parts() const;
};

// Checks that `header` was baked from `scene`: the same scene name, light shape, light
// orientation, and (rect, disk) centre and size. INVALID_ARGUMENT naming `pdsm_path` and the
// header field that differs. (A PDSM of another scene shades garbage, so it is an error;
// --allow-mismatch in the viewer turns it into a warning.)
absl::Status CheckPdsmMatchesScene(const Scene& scene, const PdsmHeader& header,
                                   const std::string& pdsm_path);

// light_from_world of a light frame as a matrix (double).
glm::dmat4 LightFromWorldMatrix(const LightFrame& frame);

// The scene's meshes in the PDSM's light space, flat-shaded, one colour each.
std::vector<DrawMesh> BuildBakedMeshes(const Scene& scene, const LightFrame& frame);

// Fills `view`'s baked meshes and bounds from its scene and its PDSM's light frame.
void PrepareViewScene(ViewScene* view);

// A UV sphere of radius 1 at the origin.
DrawMesh MakeUnitSphere(int segments = 48, int rings = 24);

// A mesh file (Assimp) as an object-space DrawMesh; `context` names the flag for errors.
absl::StatusOr<DrawMesh> LoadObjectMesh(const std::string& path, const std::string& context);

// Axis-aligned bounds of the scene's meshes (world); only of casters with `casters_only`
// (all meshes when none casts).
void SceneBounds(const Scene& scene, bool casters_only, glm::dvec3* min_world,
                 glm::dvec3* max_world);

}  // namespace pdsm::view

#endif  // PDSM_CLIENT_VIEW_VIEW_SCENE_H_
