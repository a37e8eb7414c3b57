// A world file as the scene (issue #16 item 1): `pdsm bake world.gltf` bakes the file's meshes
// with the lights the file holds, where a scene JSON would name them. The file is read with
// Assimp, as a scene JSON's mesh `path` is (core/scene/mesh_file.h), and turned into the scene
// message a JSON file would give: one mesh entry naming the file (every node, its transform
// applied, role CASTER_AND_RECEIVER where a node's extras set none: core/scene/node_roles.h)
// and one light per light of the file that pdsm can bake.
//
// Lights (glTF KHR_lights_punctual; what Assimp reports for other formats), in world space
// (the light's node transform applied, as the meshes' are), named by their node:
//   directional -> sun, angularDiameterDeg from the node's extras, else 0.53 (the sun's);
//   spot        -> spot, the outer cone angle as coneHalfAngleDeg, radius from the node's
//                  extras, else kDefaultPunctualRadius (glTF's punctual lights have no size);
//   point       -> sphere (core/scene/sphere_faces.h), radius from the node's extras, else
//                  kDefaultPunctualRadius;
//   area        -> rect of the light's size, its up as the rect's;
//   ambient and others -> not baked (no shadow to bake): named in one warning per kind.
// A light node's numeric extras named as BakeParams' JSON fields (samples,
// shadowMapResolution, epsilon, depthBias, tileSize, adaptiveTolerance, adaptiveMinSamples)
// are that light's own `bake`, as a scene JSON's lights[i].bake. Names are made to fit
// Light.name ([A-Za-z0-9_.-], unique: other characters become '_', repeats get "-2", ...).
#ifndef PDSM_CORE_SCENE_WORLD_FILE_H_
#define PDSM_CORE_SCENE_WORLD_FILE_H_

#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "pdsm/v1/scene.pb.h"

namespace pdsm {

// World units: a glTF spot or point light's radius when its node's extras give none (5 cm in glTF's
// metres: a lamp's bulb).
inline constexpr double kDefaultPunctualRadius = 0.05;
// Degrees: a directional light's angular diameter when its node's extras give none.
inline constexpr double kDefaultSunDiameterDeg = 0.53;

// Whether `path` is read as a world file (by extension, any case: .gltf .glb .fbx .obj .dae)
// rather than as a scene JSON.
bool IsWorldFile(const std::string& path);

// The scene message of world file `path`: name (the file's stem), meshes (the file itself, by
// its name: relative to the file's folder), lights; `bake` left empty (every default).
// `warnings` gets one line per kind of light left out. Errors name the file: NOT_FOUND for no
// file, INVALID_ARGUMENT for a file Assimp cannot read, a light node whose extras are not
// valid bake fields, or a file with no light pdsm can bake.
absl::StatusOr<pdsm::v1::Scene> ReadWorldFile(const std::string& path,
                                              std::vector<std::string>* warnings);

}  // namespace pdsm

#endif  // PDSM_CORE_SCENE_WORLD_FILE_H_
