// A small glTF world for alpha-tested casters (issue #16 item 2), written by tests: a card over
// a ground, the card's texture opaque on one part and clear elsewhere, so that where its shadow
// falls says which texels were tested and how UVs map onto them.
//
//   ground: the quad x, z in [-3, 3] at y = 0, opaque (material "ground");
//   card:   the quad x, z in [-1, 1] at y = kCardHeight, u = (x + 1) / 2, v = (z + 1) / 2 (v = 0
//           at the image's top row), material "card" with the options' alpha mode;
//   texture (64 x 64, gray + alpha): opaque where u < 1/2 or v < 1/4, clear elsewhere. Seen
//   from a light straight above, the card's shadow covers x < 0, and x >= 0 only for z < -1/2.
#ifndef PDSM_TESTS_ALPHA_CARD_H_
#define PDSM_TESTS_ALPHA_CARD_H_

#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "absl/strings/escaping.h"
#include "absl/strings/str_cat.h"
#include "core/util/png_writer.h"

namespace pdsm::testing {

inline constexpr double kCardHeight = 1.0;

struct AlphaCardOptions {
  std::string alpha_mode = "MASK";  // "OPAQUE", "MASK" or "BLEND"
  double alpha_cutoff = -1;         // < 0: not written (glTF's default, 0.5)
  double factor_alpha = 1;          // the base-colour factor's alpha
  bool texture = true;              // false: no base-colour texture
  bool texcoords = true;            // false: the card has no TEXCOORD_0
  std::string texture_uri;          // empty: the PNG embedded as a data URI
};

// The card texture's PNG bytes (see above).
inline std::string AlphaCardPng() {
  constexpr int kSize = 64;
  std::vector<uint8_t> gray_alpha;
  for (int y = 0; y < kSize; ++y) {
    for (int x = 0; x < kSize; ++x) {
      gray_alpha.push_back(128);
      gray_alpha.push_back(x < kSize / 2 || y < kSize / 4 ? 255 : 0);
    }
  }
  return *EncodeGrayAlphaPng(kSize, kSize, gray_alpha);
}

// The glTF file's text.
inline std::string AlphaCardGltf(const AlphaCardOptions& options = {}) {
  std::string blob;
  const auto floats = [&](std::initializer_list<float> values) {
    for (float f : values) blob.append(reinterpret_cast<const char*>(&f), 4);
  };
  const auto uints = [&](std::initializer_list<uint32_t> values) {
    for (uint32_t u : values) blob.append(reinterpret_cast<const char*>(&u), 4);
  };
  const float h = static_cast<float>(kCardHeight);
  floats({-3, 0, -3, 3, 0, -3, 3, 0, 3, -3, 0, 3});  // ground positions: bytes 0..47
  uints({0, 2, 1, 0, 3, 2});                         // ground indices: 48..71
  floats({-1, h, -1, 1, h, -1, 1, h, 1, -1, h, 1});  // card positions: 72..119
  uints({0, 2, 1, 0, 3, 2});                         // card indices: 120..143
  floats({0, 0, 1, 0, 1, 1, 0, 1});                  // card UVs: 144..175
  const std::string attributes =
      options.texcoords ? R"({"POSITION": 2, "TEXCOORD_0": 4})" : R"({"POSITION": 2})";
  std::string card_material = absl::StrCat(R"({"name": "card", "alphaMode": ")", options.alpha_mode,
                                           R"(", "doubleSided": true)");
  if (options.alpha_cutoff >= 0)
    absl::StrAppend(&card_material, R"(, "alphaCutoff": )", options.alpha_cutoff);
  absl::StrAppend(&card_material, R"(, "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, )",
                  options.factor_alpha, "]");
  if (options.texture) absl::StrAppend(&card_material, R"(, "baseColorTexture": {"index": 0})");
  absl::StrAppend(&card_material, "}}");
  const std::string image_uri =
      options.texture_uri.empty()
          ? absl::StrCat("data:image/png;base64,", absl::Base64Escape(AlphaCardPng()))
          : options.texture_uri;
  return absl::StrCat(
      R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0, 1]}],)",
      R"( "nodes": [{"name": "ground", "mesh": 0}, {"name": "card", "mesh": 1}],)",
      R"( "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1,)",
      R"( "material": 0}]}, {"primitives": [{"attributes": )", attributes,
      R"(, "indices": 3, "material": 1}]}],)", R"( "materials": [{"name": "ground"}, )",
      card_material, "],", R"( "textures": [{"source": 0, "sampler": 0}],)",
      R"( "samplers": [{"magFilter": 9729, "minFilter": 9729, "wrapS": 33071, "wrapT": 33071}],)",
      R"( "images": [{"uri": ")", image_uri, R"("}],)", R"( "accessors": [)",
      R"({"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",)",
      R"( "min": [-3, 0, -3], "max": [3, 0, 3]},)",
      R"( {"bufferView": 1, "componentType": 5125, "count": 6, "type": "SCALAR"},)",
      R"( {"bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC3",)",
      R"( "min": [-1, )", h, R"(, -1], "max": [1, )", h, R"(, 1]},)",
      R"( {"bufferView": 3, "componentType": 5125, "count": 6, "type": "SCALAR"},)",
      R"( {"bufferView": 4, "componentType": 5126, "count": 4, "type": "VEC2"}],)",
      R"( "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 48},)",
      R"( {"buffer": 0, "byteOffset": 48, "byteLength": 24},)",
      R"( {"buffer": 0, "byteOffset": 72, "byteLength": 48},)",
      R"( {"buffer": 0, "byteOffset": 120, "byteLength": 24},)",
      R"( {"buffer": 0, "byteOffset": 144, "byteLength": 32}],)", R"( "buffers": [{"byteLength": )",
      blob.size(), R"(, "uri": "data:application/octet-stream;base64,)", absl::Base64Escape(blob),
      R"("}]})");
}

// A scene JSON baking `gltf_file` (relative to the scene's folder) under a small rect light
// straight above the card (0.2 across, at y = 4): a sharp shadow of the card's texture.
inline std::string AlphaCardSceneJson(const std::string& gltf_file, int resolution = 64,
                                      int samples = 16) {
  return absl::StrCat(R"({"name": "card", "meshes": [{"path": ")", gltf_file, R"("}],)",
                      R"( "light": {"rect": {"center": [0, 4, 0], "normal": [0, -1, 0],)",
                      R"( "up": [0, 0, 1], "size": [0.2, 0.2]}},)", R"( "bake": {"resolution": [)",
                      resolution, ", ", resolution, R"(], "samples": )", samples,
                      R"(, "tileSize": 16}})");
}

}  // namespace pdsm::testing

#endif  // PDSM_TESTS_ALPHA_CARD_H_
