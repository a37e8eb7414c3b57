#include "core/scene/material_masks.h"

#include <assimp/GltfMaterial.h>
#include <assimp/material.h>
#include <assimp/scene.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string_view>
#include <utility>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "core/util/png_reader.h"

namespace pdsm::internal {
namespace {

// Which channel of the texture holds coverage.
enum class Coverage { kAlpha, kAlphaElseGray };

// What a material asks for: a texture (empty path: none) scaled by `factor`, tested at
// `cutoff`; or nothing (opaque).
struct AlphaRule {
  bool tested = false;
  std::string texture;  // Assimp's path ("*0" for an embedded texture), empty for none
  Coverage coverage = Coverage::kAlpha;
  double factor = 1;
  double cutoff = 0.5;
  unsigned uv_channel = 0;
  TextureWrap wrap_u = TextureWrap::kRepeat, wrap_v = TextureWrap::kRepeat;
};

TextureWrap WrapOf(aiTextureMapMode mode) {
  switch (mode) {
    case aiTextureMapMode_Clamp:
    case aiTextureMapMode_Decal:
      return TextureWrap::kClampToEdge;
    case aiTextureMapMode_Mirror:
      return TextureWrap::kMirroredRepeat;
    default:
      return TextureWrap::kRepeat;
  }
}

// The first texture of `type`, with its UV channel and wrap modes; false when there is none.
bool FirstTexture(const aiMaterial& material, aiTextureType type, AlphaRule* rule) {
  if (material.GetTextureCount(type) == 0) return false;
  aiString path;
  unsigned uv_index = 0;
  aiTextureMapMode modes[2] = {aiTextureMapMode_Wrap, aiTextureMapMode_Wrap};
  if (material.GetTexture(type, 0, &path, nullptr, &uv_index, nullptr, nullptr, modes) !=
      aiReturn_SUCCESS) {
    return false;
  }
  rule->texture = path.C_Str();
  rule->uv_channel = uv_index;
  rule->wrap_u = WrapOf(modes[0]);
  rule->wrap_v = WrapOf(modes[1]);
  return true;
}

std::string MaterialName(const aiMaterial& material, unsigned index) {
  aiString name;
  if (material.Get(AI_MATKEY_NAME, name) == aiReturn_SUCCESS && name.length > 0) {
    return absl::StrCat("\"", name.C_Str(), "\"");
  }
  return absl::StrCat("#", index);
}

AlphaRule RuleOf(const aiMaterial& material, const std::string& name,
                 std::vector<std::string>* blend_materials,
                 std::vector<std::string>* translucent_materials) {
  AlphaRule rule;
  aiString mode;
  if (material.Get(AI_MATKEY_GLTF_ALPHAMODE, mode) == aiReturn_SUCCESS) {  // glTF
    const std::string_view m = mode.C_Str();
    if (m != "MASK" && m != "BLEND") return rule;
    rule.tested = true;
    if (m == "MASK") {
      float cutoff = 0.5f;
      if (material.Get(AI_MATKEY_GLTF_ALPHACUTOFF, cutoff) == aiReturn_SUCCESS)
        rule.cutoff = cutoff;
    } else {
      blend_materials->push_back(name);
    }
    aiColor4D base(1, 1, 1, 1);
    if (material.Get(AI_MATKEY_BASE_COLOR, base) == aiReturn_SUCCESS) rule.factor = base.a;
    if (!FirstTexture(material, aiTextureType_BASE_COLOR, &rule)) {
      FirstTexture(material, aiTextureType_DIFFUSE, &rule);
    }
    return rule;
  }
  // OBJ/MTL (map_d, d), FBX and the others: an opacity texture, an opacity factor.
  float opacity = 1;
  material.Get(AI_MATKEY_OPACITY, opacity);
  rule.factor = opacity;
  rule.coverage = Coverage::kAlphaElseGray;
  if (FirstTexture(material, aiTextureType_OPACITY, &rule)) {
    rule.tested = true;
  } else if (opacity < 1) {
    rule.tested = true;
    translucent_materials->push_back(name);
  }
  return rule;
}

absl::StatusOr<std::string> ReadBytes(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) return absl::InvalidArgumentError(absl::StrCat("cannot open \"", file.string(), "\""));
  std::ostringstream bytes;
  bytes << in.rdbuf();
  if (!in.good() && !in.eof()) {
    return absl::InvalidArgumentError(absl::StrCat("cannot read \"", file.string(), "\""));
  }
  return std::move(bytes).str();
}

// The coverage texels of a rule's texture, row 0 at the top.
absl::StatusOr<GrayAlphaImage> ReadTexture(const aiScene& scene, const std::string& path,
                                           const AlphaRule& rule) {
  if (const aiTexture* embedded = scene.GetEmbeddedTexture(rule.texture.c_str())) {
    if (embedded->mHeight == 0) {  // a compressed file held in memory
      return DecodePngGrayAlpha(
          std::string_view(reinterpret_cast<const char*>(embedded->pcData), embedded->mWidth),
          kMaxAlphaMaskSide);
    }
    if (embedded->mWidth > static_cast<unsigned>(kMaxAlphaMaskSide) ||
        embedded->mHeight > static_cast<unsigned>(kMaxAlphaMaskSide)) {
      return absl::InvalidArgumentError(absl::StrCat("the image is ", embedded->mWidth, "x",
                                                     embedded->mHeight, " texels; at most ",
                                                     kMaxAlphaMaskSide, " a side are read"));
    }
    GrayAlphaImage image;  // raw BGRA texels
    image.width = static_cast<int>(embedded->mWidth);
    image.height = static_cast<int>(embedded->mHeight);
    image.has_alpha = true;
    const size_t count = static_cast<size_t>(image.width) * image.height;
    image.gray_alpha.resize(2 * count);
    for (size_t i = 0; i < count; ++i) {
      const aiTexel& t = embedded->pcData[i];
      image.gray_alpha[2 * i] = static_cast<uint8_t>((t.r + t.g + t.b) / 3);
      image.gray_alpha[2 * i + 1] = t.a;
    }
    return image;
  }
  std::filesystem::path file(rule.texture);
  if (file.is_relative()) file = std::filesystem::path(path).parent_path() / file;
  absl::StatusOr<std::string> bytes = ReadBytes(file.lexically_normal());
  if (!bytes.ok()) return bytes.status();
  return DecodePngGrayAlpha(*bytes, kMaxAlphaMaskSide);
}

// A mask no point passes: the material casts nothing.
std::shared_ptr<const AlphaMask> NeverCasts(const std::string& label) {
  auto mask = std::make_shared<AlphaMask>();
  mask->label = label;
  mask->width = mask->height = 1;
  mask->alpha = {0};
  return mask;
}

}  // namespace

absl::StatusOr<std::vector<MaterialAlpha>> ReadMaterialAlphas(
    const aiScene& scene, const std::string& path, std::vector<std::string>* blend_materials,
    std::vector<std::string>* translucent_materials) {
  std::vector<MaterialAlpha> alphas(scene.mNumMaterials);
  // One mask per (texture, coverage, cutoff, wraps): a file's cards usually share one atlas.
  std::map<std::tuple<std::string, int, double, int, int>, std::shared_ptr<const AlphaMask>> made;
  for (unsigned m = 0; m < scene.mNumMaterials; ++m) {
    const aiMaterial& material = *scene.mMaterials[m];
    const std::string name = MaterialName(material, m);
    const AlphaRule rule = RuleOf(material, name, blend_materials, translucent_materials);
    if (!rule.tested) continue;
    const std::string label = absl::StrCat("material ", name);
    if (!(std::isfinite(rule.cutoff) && rule.cutoff >= 0) ||
        !(std::isfinite(rule.factor) && rule.factor >= 0)) {
      return absl::InvalidArgumentError(
          absl::StrCat(label, ": the alpha cutoff and factor must be finite and >= 0 (got ",
                       rule.cutoff, " and ", rule.factor, ")"));
    }
    if (rule.cutoff == 0) continue;  // every point passes: opaque
    // alpha_texture * factor >= cutoff  <=>  alpha_texture >= cutoff / factor.
    const double cutoff = rule.factor > 0 ? rule.cutoff / rule.factor : 2.0;
    MaterialAlpha& alpha = alphas[m];
    alpha.uv_channel = rule.uv_channel;
    if (cutoff > 1) {  // no texel can pass: no texture is read, no UVs needed
      alpha.mask = NeverCasts(label);
      continue;
    }
    if (rule.texture.empty()) continue;               // the factor alone passes: opaque
    if (!(static_cast<float>(cutoff) > 0)) continue;  // below float's range: every point passes
    const auto key = std::make_tuple(rule.texture, static_cast<int>(rule.coverage), cutoff,
                                     static_cast<int>(rule.wrap_u), static_cast<int>(rule.wrap_v));
    alpha.needs_uvs = true;
    if (auto it = made.find(key); it != made.end()) {
      alpha.mask = it->second;
      continue;
    }
    absl::StatusOr<GrayAlphaImage> image = ReadTexture(scene, path, rule);
    if (!image.ok()) {
      return absl::InvalidArgumentError(
          absl::StrCat(label, ": texture \"", rule.texture, "\": ", image.status().message()));
    }
    auto mask = std::make_shared<AlphaMask>();
    mask->label = absl::StrCat(label, " (", rule.texture, ")");
    mask->width = image->width;
    mask->height = image->height;
    mask->wrap_u = rule.wrap_u;
    mask->wrap_v = rule.wrap_v;
    mask->cutoff = static_cast<float>(cutoff);
    const bool use_gray = rule.coverage == Coverage::kAlphaElseGray && !image->has_alpha;
    mask->alpha.resize(image->gray_alpha.size() / 2);
    for (size_t i = 0; i < mask->alpha.size(); ++i) {
      mask->alpha[i] = image->gray_alpha[2 * i + (use_gray ? 0 : 1)];
    }
    made.emplace(key, mask);
    alpha.mask = std::move(mask);
    alpha.needs_uvs = true;
  }
  return alphas;
}

}  // namespace pdsm::internal
