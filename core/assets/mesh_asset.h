// Mesh assets: the canonical binary form of a triangle mesh that `pdsm submit` uploads, and the
// SHA-256 that addresses it. The coordinator and the workers store meshes by content and never
// open a path sent by a remote client.
//
// Byte layout (little-endian, no padding):
//   char[8]  magic "PDSMMESH"
//   uint32   version (1: opaque; 2: with alpha masks)
//   uint64   vertex_count
//   uint64   index_count       (3 per triangle)
//   float64  x, y, z           vertex_count times, model space
//   uint32   index             index_count times, each < vertex_count
// Version 2 only (a mesh with alpha-tested triangles, core/scene/alpha_mask.h), then:
//   uint32   mask_count        1 .. 65535
//   per mask: uint32 width, uint32 height, uint8 wrap_u, uint8 wrap_v, float32 cutoff,
//             uint8 alpha[width * height]
//   float32  u, v              vertex_count times
//   uint16   mask              index_count / 3 times, each <= mask_count (0: opaque)
// An opaque mesh is written as version 1, so its bytes and hash are what they were before
// masks existed. The same mesh always encodes to the same bytes, which is what makes the hash
// a content address. Mask labels are not stored (decoded masks are labelled "mask k").
#ifndef PDSM_CORE_ASSETS_MESH_ASSET_H_
#define PDSM_CORE_ASSETS_MESH_ASSET_H_

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>

#include "absl/status/statusor.h"
#include "core/scene/mesh_file.h"

struct evp_md_ctx_st;  // OpenSSL's EVP_MD_CTX; OpenSSL is private to pdsm_core

namespace pdsm {

inline constexpr uint32_t kMeshAssetVersion = 1;
inline constexpr uint32_t kMaskedMeshAssetVersion = 2;

// The canonical bytes of `mesh`. Encodes what it is given; DecodeMeshAsset is the validator.
std::string EncodeMeshAsset(const MeshFileData& mesh);

// Parses and validates a mesh asset. `context` prefixes every message, e.g.
// "job 7: meshes[0] (asset 0123456789ab)".
// Errors: INVALID_ARGUMENT "<context>: ..." for a bad magic or version, counts that do not
// match the byte length exactly (checked before anything is allocated), an index count that is
// zero or not a multiple of 3, an index >= vertex_count, a non-finite coordinate; in version 2
// a mask that is not Valid(), a non-finite UV, a triangle's mask > mask_count.
absl::StatusOr<MeshFileData> DecodeMeshAsset(std::string_view bytes, const std::string& context);

// Lowercase hex SHA-256 of `bytes` (64 characters).
std::string Sha256Hex(std::string_view bytes);

// True for exactly 64 characters of [0-9a-f]: what Sha256Hex returns and what addresses an asset.
bool IsSha256Hex(std::string_view s);

// SHA-256 of data that arrives in pieces (streamed uploads). Update(a); Update(b) gives the
// hash of a + b. Not thread-safe; movable, not copyable.
class Sha256 {
 public:
  Sha256();
  ~Sha256();
  Sha256(Sha256&&) noexcept = default;  // the moved-from object may only be destroyed
  Sha256& operator=(Sha256&&) noexcept = default;
  Sha256(const Sha256&) = delete;
  Sha256& operator=(const Sha256&) = delete;

  void Update(std::string_view bytes);
  // Lowercase hex of everything given to Update since construction or the last FinalHex, and
  // starts over with no data.
  std::string FinalHex();

 private:
  struct ContextDeleter {
    void operator()(evp_md_ctx_st* context) const;
  };
  std::unique_ptr<evp_md_ctx_st, ContextDeleter> context_;
};

}  // namespace pdsm

#endif  // PDSM_CORE_ASSETS_MESH_ASSET_H_
