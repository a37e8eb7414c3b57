// A small glTF world whose nodes set their roles in extras (issue #16 item 1; core/scene/
// node_roles.h), written by tests: a sun straight down over a ground and two slabs, so that
// where a slab's shadow is (or is not) says whether its node cast.
//
//   ground: the quad x, z in [-3, 3] at y = 0, extras role RECEIVER_ONLY;
//   props:  a group node (no mesh) with the options' role, whose child
//   roof:   the quad x in [0.5, 2.5], z in [-1, 1] at y = 1, has no role of its own;
//   wall:   the quad x in [-2.5, -0.5], z in [-1, 1] at y = 1, no role (the entry's);
//   sun:    a directional light along -y, 2 degrees across.
// Every quad has TEXCOORD_0 = (x, z) mapped from its extent to [0, 1]^2 (a lightmap UV set).
#ifndef PDSM_TESTS_ROLE_WORLD_H_
#define PDSM_TESTS_ROLE_WORLD_H_

#include <cstdint>
#include <initializer_list>
#include <string>

#include "absl/strings/escaping.h"
#include "absl/strings/str_cat.h"

namespace pdsm::testing {

// The props group's extras: "" writes none (the roof then takes the entry's role); a JSON
// value otherwise, e.g. "\"RECEIVER_ONLY\"", "\"receiver\"", "3".
inline std::string RoleWorldGltf(const std::string& props_role_json = "\"RECEIVER_ONLY\"",
                                 bool ground_role = true) {
  std::string blob;
  const auto floats = [&](std::initializer_list<float> values) {
    for (float f : values) blob.append(reinterpret_cast<const char*>(&f), 4);
  };
  const auto uints = [&](std::initializer_list<uint32_t> values) {
    for (uint32_t u : values) blob.append(reinterpret_cast<const char*>(&u), 4);
  };
  // Per quad: 4 positions (48 bytes), 4 UVs (32), 6 indices (24): 104 bytes.
  const auto quad = [&](float x0, float x1, float z0, float z1, float y) {
    floats({x0, y, z0, x1, y, z0, x1, y, z1, x0, y, z1});
    floats({0, 0, 1, 0, 1, 1, 0, 1});
    uints({0, 2, 1, 0, 3, 2});
  };
  quad(-3, 3, -3, 3, 0);       // ground
  quad(0.5, 2.5, -1, 1, 1);    // roof
  quad(-2.5, -0.5, -1, 1, 1);  // wall
  std::string accessors, views, meshes;
  for (int q = 0; q < 3; ++q) {
    const int base = 104 * q;
    absl::StrAppend(&views, q > 0 ? ", " : "", R"({"buffer": 0, "byteOffset": )", base,
                    R"(, "byteLength": 48}, {"buffer": 0, "byteOffset": )", base + 48,
                    R"(, "byteLength": 32}, {"buffer": 0, "byteOffset": )", base + 80,
                    R"(, "byteLength": 24})");
    const float y = q == 0 ? 0.0f : 1.0f;
    const float x0 = q == 0 ? -3 : (q == 1 ? 0.5f : -2.5f),
                x1 = q == 0 ? 3 : (q == 1 ? 2.5f : -0.5f);
    const float z = q == 0 ? 3 : 1;
    absl::StrAppend(&accessors, q > 0 ? ", " : "", R"({"bufferView": )", 3 * q,
                    R"(, "componentType": 5126, "count": 4, "type": "VEC3", "min": [)", x0, ", ", y,
                    ", ", -z, R"(], "max": [)", x1, ", ", y, ", ", z, R"(]}, {"bufferView": )",
                    3 * q + 1, R"(, "componentType": 5126, "count": 4, "type": "VEC2"},)",
                    R"( {"bufferView": )", 3 * q + 2,
                    R"(, "componentType": 5125, "count": 6, "type": "SCALAR"})");
    absl::StrAppend(&meshes, q > 0 ? ", " : "", R"({"primitives": [{"attributes": {"POSITION": )",
                    3 * q, R"(, "TEXCOORD_0": )", 3 * q + 1, R"(}, "indices": )", 3 * q + 2, "}]}");
  }
  const std::string props_extras =
      props_role_json.empty() ? "" : absl::StrCat(R"(, "extras": {"role": )", props_role_json, "}");
  const std::string ground_extras = ground_role ? R"(, "extras": {"role": "RECEIVER_ONLY"})" : "";
  return absl::StrCat(
      R"({"asset": {"version": "2.0"}, "extensionsUsed": ["KHR_lights_punctual"],)",
      R"( "extensions": {"KHR_lights_punctual": {"lights": [{"name": "sun", "type": "directional"}]}},)",
      R"( "scene": 0, "scenes": [{"nodes": [0, 1, 3, 4]}], "nodes": [)",
      R"({"name": "ground", "mesh": 0)", ground_extras, "},",
      R"( {"name": "props", "children": [2])", props_extras, "},",
      R"( {"name": "roof", "mesh": 1}, {"name": "wall", "mesh": 2},)",
      R"( {"name": "sun", "rotation": [-0.70710678, 0, 0, 0.70710678],)",
      R"( "extensions": {"KHR_lights_punctual": {"light": 0}}, "extras": {"angularDiameterDeg": 2}}],)",
      R"( "meshes": [)", meshes, R"(], "accessors": [)", accessors, R"(], "bufferViews": [)", views,
      R"(], "buffers": [{"byteLength": )", blob.size(),
      R"(, "uri": "data:application/octet-stream;base64,)", absl::Base64Escape(blob), R"("}]})");
}

}  // namespace pdsm::testing

#endif  // PDSM_TESTS_ROLE_WORLD_H_
