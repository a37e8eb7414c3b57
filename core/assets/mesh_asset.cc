#include "core/assets/mesh_asset.h"

#include <openssl/evp.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <utility>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "core/util/little_endian.h"

namespace pdsm {
namespace {

constexpr char kMagic[8] = {'P', 'D', 'S', 'M', 'M', 'E', 'S', 'H'};
// magic, version, vertex_count, index_count.
constexpr size_t kHeaderBytes = sizeof(kMagic) + 4 + 8 + 8;
constexpr size_t kVertexBytes = 3 * 8;                  // float64 x, y, z
constexpr size_t kIndexBytes = 4;                       // uint32
constexpr size_t kMaskHeaderBytes = 4 + 4 + 1 + 1 + 4;  // width, height, wraps, cutoff
constexpr size_t kUvBytes = 2 * 4;                      // float32 u, v

// The JSON spellings of the non-finite values, as in scene messages.
std::string FormatDouble(double x) {
  if (std::isnan(x)) return "NaN";
  if (std::isinf(x)) return x > 0 ? "Infinity" : "-Infinity";
  return absl::StrCat(x);
}

std::string Hex(const unsigned char* digest, unsigned int size) {
  constexpr char kDigits[] = "0123456789abcdef";
  std::string hex(2 * size, '\0');
  for (unsigned int i = 0; i < size; ++i) {
    hex[2 * i] = kDigits[digest[i] >> 4];
    hex[2 * i + 1] = kDigits[digest[i] & 0xf];
  }
  return hex;
}

// OpenSSL fails SHA-256 over memory only when it cannot allocate or is broken; there is no
// caller that could do anything sensible with such an error.
void CheckOpenSsl(int ok) {
  if (ok != 1) std::abort();
}

// Version 2's mask section: `left` bytes follow in `in`, all of them the section's.
absl::Status DecodeMasks(ByteReader& in, size_t left, uint64_t vertex_count,
                         uint64_t triangle_count, MeshFileData* mesh) {
  const auto invalid = [](absl::string_view what) { return absl::InvalidArgumentError(what); };
  const auto truncated = [&] {
    return invalid(absl::StrCat("size mismatch: the alpha masks, ", vertex_count, " UVs and ",
                                triangle_count, " triangle masks need more than the ", left,
                                " bytes left"));
  };
  if (left < 4) return truncated();
  const uint32_t mask_count = in.U32();
  left -= 4;
  if (mask_count == 0 || mask_count > UINT16_MAX) {
    return invalid(
        absl::StrCat("the mask count must be in [1, ", UINT16_MAX, "] (got ", mask_count, ")"));
  }
  for (uint32_t k = 0; k < mask_count; ++k) {
    if (left < kMaskHeaderBytes) return truncated();
    auto mask = std::make_shared<AlphaMask>();
    const uint32_t width = in.U32(), height = in.U32();
    const uint8_t wrap_u = in.U8(), wrap_v = in.U8();
    mask->cutoff = in.F32();
    left -= kMaskHeaderBytes;
    mask->label = absl::StrCat("mask ", k + 1);
    if (width == 0 || height == 0 || width > kMaxAlphaMaskSide || height > kMaxAlphaMaskSide ||
        wrap_u > 2 || wrap_v > 2 || !(mask->cutoff > 0 && mask->cutoff <= 1)) {
      return invalid(absl::StrCat("mask ", k + 1, ": ", width, "x", height, " texels (at most ",
                                  kMaxAlphaMaskSide, " a side), wraps ", int{wrap_u}, " ",
                                  int{wrap_v}, " (0..2), cutoff ", mask->cutoff,
                                  " (in (0, 1]): not a mask"));
    }
    const size_t texels = size_t{width} * height;
    if (left < texels) return truncated();
    mask->width = static_cast<int>(width);
    mask->height = static_cast<int>(height);
    mask->wrap_u = static_cast<TextureWrap>(wrap_u);
    mask->wrap_v = static_cast<TextureWrap>(wrap_v);
    mask->alpha.resize(texels);
    in.Bytes(reinterpret_cast<char*>(mask->alpha.data()), texels);
    left -= texels;
    mesh->masks.push_back(std::move(mask));
  }
  if (left != vertex_count * kUvBytes + triangle_count * 2) {
    return invalid(absl::StrCat(
        "size mismatch: ", vertex_count, " UVs and ", triangle_count, " triangle masks need ",
        vertex_count * kUvBytes + triangle_count * 2, " bytes after the masks (got ", left, ")"));
  }
  mesh->uvs.reserve(vertex_count);
  for (uint64_t v = 0; v < vertex_count; ++v) {
    const float u = in.F32(), w = in.F32();
    if (!std::isfinite(u) || !std::isfinite(w)) {
      return invalid(absl::StrCat("the UV of vertex ", v, " must be finite (got ", FormatDouble(u),
                                  ", ", FormatDouble(w), ")"));
    }
    mesh->uvs.emplace_back(u, w);
  }
  mesh->triangle_masks.reserve(triangle_count);
  for (uint64_t t = 0; t < triangle_count; ++t) {
    const uint16_t k = in.U16();
    if (k > mask_count) {
      return invalid(absl::StrCat("triangle ", t, "'s mask must be <= ", mask_count,
                                  ", the mask count (got ", k, ")"));
    }
    mesh->triangle_masks.push_back(k);
  }
  return absl::OkStatus();
}

}  // namespace

std::string EncodeMeshAsset(const MeshFileData& mesh) {
  size_t size =
      kHeaderBytes + mesh.positions.size() * kVertexBytes + mesh.indices.size() * kIndexBytes;
  if (mesh.has_masks()) {
    size += 4;
    for (const auto& mask : mesh.masks) size += kMaskHeaderBytes + mask->alpha.size();
    size += mesh.uvs.size() * kUvBytes + mesh.triangle_masks.size() * 2;
  }
  std::string bytes(size, '\0');
  ByteWriter out(bytes.data());
  out.Bytes(kMagic, sizeof(kMagic));
  out.U32(mesh.has_masks() ? kMaskedMeshAssetVersion : kMeshAssetVersion);
  out.U64(mesh.positions.size());
  out.U64(mesh.indices.size());
  for (const glm::dvec3& p : mesh.positions) {
    out.F64(p.x);
    out.F64(p.y);
    out.F64(p.z);
  }
  for (const uint32_t index : mesh.indices) out.U32(index);
  if (mesh.has_masks()) {
    out.U32(static_cast<uint32_t>(mesh.masks.size()));
    for (const auto& mask : mesh.masks) {
      out.U32(static_cast<uint32_t>(mask->width));
      out.U32(static_cast<uint32_t>(mask->height));
      out.U8(static_cast<uint8_t>(mask->wrap_u));
      out.U8(static_cast<uint8_t>(mask->wrap_v));
      out.F32(mask->cutoff);
      out.Bytes(reinterpret_cast<const char*>(mask->alpha.data()), mask->alpha.size());
    }
    for (const glm::vec2& uv : mesh.uvs) {
      out.F32(uv.x);
      out.F32(uv.y);
    }
    for (const uint16_t k : mesh.triangle_masks) out.U16(k);
  }
  return bytes;
}

absl::StatusOr<MeshFileData> DecodeMeshAsset(std::string_view bytes, const std::string& context) {
  const auto invalid = [&](absl::string_view what) {
    return absl::InvalidArgumentError(absl::StrCat(context, ": ", what));
  };
  const size_t size = bytes.size();
  // A prefix of the magic is a truncated asset, not a foreign file.
  if (size > 0 && std::memcmp(bytes.data(), kMagic, std::min(size, sizeof(kMagic))) != 0) {
    return invalid("not a mesh asset (bad magic)");
  }
  if (size < kHeaderBytes) {
    return invalid(absl::StrCat("truncated mesh asset (", size, " bytes, the header alone has ",
                                kHeaderBytes, ")"));
  }
  ByteReader in(bytes.data() + sizeof(kMagic));
  const uint32_t version = in.U32();
  if (version != kMeshAssetVersion && version != kMaskedMeshAssetVersion) {
    return invalid(absl::StrCat("unsupported mesh asset version ", version, " (this build reads ",
                                kMeshAssetVersion, " and ", kMaskedMeshAssetVersion, ")"));
  }
  const bool masked = version == kMaskedMeshAssetVersion;
  const uint64_t vertex_count = in.U64();
  const uint64_t index_count = in.U64();
  // Each count is bounded by the bytes left before it is multiplied: no overflow, and nothing
  // is allocated for counts the blob cannot hold.
  const size_t body = size - kHeaderBytes;
  // Version 2's mask section follows the opaque mesh: it needs bytes after it.
  if (vertex_count > body / kVertexBytes ||
      index_count > (body - vertex_count * kVertexBytes) / kIndexBytes ||
      (masked ? vertex_count * kVertexBytes + index_count * kIndexBytes >= body
              : vertex_count * kVertexBytes + index_count * kIndexBytes != body)) {
    return invalid(absl::StrCat("size mismatch: ", vertex_count, " vertices and ", index_count,
                                " indices need ", kHeaderBytes, " + ", vertex_count, " * ",
                                kVertexBytes, " + ", index_count, " * ", kIndexBytes,
                                " bytes (got ", size, ")"));
  }
  if (index_count == 0) return invalid("no triangles (got 0 indices)");
  if (index_count % 3 != 0) {
    return invalid(absl::StrCat("the index count must be a multiple of 3 (got ", index_count, ")"));
  }

  MeshFileData mesh;
  mesh.positions.reserve(vertex_count);
  for (uint64_t v = 0; v < vertex_count; ++v) {
    const double x = in.F64();
    const double y = in.F64();
    const double z = in.F64();
    if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z)) {
      return invalid(absl::StrCat("vertex ", v, " must be finite (got ", FormatDouble(x), ", ",
                                  FormatDouble(y), ", ", FormatDouble(z), ")"));
    }
    mesh.positions.emplace_back(x, y, z);
  }
  mesh.indices.reserve(index_count);
  for (uint64_t i = 0; i < index_count; ++i) {
    const uint32_t index = in.U32();
    if (index >= vertex_count) {
      return invalid(absl::StrCat("index ", i, " must be < ", vertex_count,
                                  ", the vertex count (got ", index, ")"));
    }
    mesh.indices.push_back(index);
  }
  if (!masked) return mesh;
  size_t left = body - vertex_count * kVertexBytes - index_count * kIndexBytes;
  if (absl::Status s = DecodeMasks(in, left, vertex_count, index_count / 3, &mesh); !s.ok()) {
    return invalid(s.message());
  }
  return mesh;
}

std::string Sha256Hex(std::string_view bytes) {
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int digest_size = 0;
  CheckOpenSsl(EVP_Digest(bytes.data(), bytes.size(), digest, &digest_size, EVP_sha256(), nullptr));
  return Hex(digest, digest_size);
}

bool IsSha256Hex(std::string_view s) {
  if (s.size() != 64) return false;
  for (const char c : s) {
    if (!((c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'))) return false;
  }
  return true;
}

void Sha256::ContextDeleter::operator()(evp_md_ctx_st* context) const { EVP_MD_CTX_free(context); }

Sha256::Sha256() : context_(EVP_MD_CTX_new()) {
  if (context_ == nullptr) std::abort();
  CheckOpenSsl(EVP_DigestInit_ex(context_.get(), EVP_sha256(), nullptr));
}

Sha256::~Sha256() = default;

void Sha256::Update(std::string_view bytes) {
  CheckOpenSsl(EVP_DigestUpdate(context_.get(), bytes.data(), bytes.size()));
}

std::string Sha256::FinalHex() {
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int digest_size = 0;
  CheckOpenSsl(EVP_DigestFinal_ex(context_.get(), digest, &digest_size));
  CheckOpenSsl(EVP_DigestInit_ex(context_.get(), EVP_sha256(), nullptr));
  return Hex(digest, digest_size);
}

}  // namespace pdsm
