#include "core/assets/mesh_asset.h"

#include <openssl/evp.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <utility>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "core/util/little_endian.h"

namespace pdsm {
namespace {

constexpr char kMagic[8] = {'P', 'D', 'S', 'M', 'M', 'E', 'S', 'H'};
// magic, version, vertex_count, index_count.
constexpr size_t kHeaderBytes = sizeof(kMagic) + 4 + 8 + 8;
constexpr size_t kVertexBytes = 3 * 8;  // float64 x, y, z
constexpr size_t kIndexBytes = 4;       // uint32

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

}  // namespace

std::string EncodeMeshAsset(const MeshFileData& mesh) {
  const size_t size =
      kHeaderBytes + mesh.positions.size() * kVertexBytes + mesh.indices.size() * kIndexBytes;
  std::string bytes(size, '\0');
  ByteWriter out(bytes.data());
  out.Bytes(kMagic, sizeof(kMagic));
  out.U32(kMeshAssetVersion);
  out.U64(mesh.positions.size());
  out.U64(mesh.indices.size());
  for (const glm::dvec3& p : mesh.positions) {
    out.F64(p.x);
    out.F64(p.y);
    out.F64(p.z);
  }
  for (const uint32_t index : mesh.indices) out.U32(index);
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
  if (version != kMeshAssetVersion) {
    return invalid(absl::StrCat("unsupported mesh asset version ", version, " (this build reads ",
                                kMeshAssetVersion, ")"));
  }
  const uint64_t vertex_count = in.U64();
  const uint64_t index_count = in.U64();
  // Each count is bounded by the bytes left before it is multiplied: no overflow, and nothing
  // is allocated for counts the blob cannot hold.
  const size_t body = size - kHeaderBytes;
  if (vertex_count > body / kVertexBytes ||
      index_count > (body - vertex_count * kVertexBytes) / kIndexBytes ||
      vertex_count * kVertexBytes + index_count * kIndexBytes != body) {
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
