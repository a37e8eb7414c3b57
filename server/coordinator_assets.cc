#include "server/coordinator_assets.h"

#include "absl/strings/str_cat.h"
#include "core/assets/mesh_asset.h"

namespace pdsm {

absl::StatusOr<std::unique_ptr<CoordinatorAssets>> CoordinatorAssets::Open(const std::string& dir,
                                                                           int64_t max_asset_bytes,
                                                                           FileSystem* fs) {
  absl::StatusOr<std::unique_ptr<AssetStore>> store = AssetStore::Open(dir, fs);
  if (!store.ok()) return store.status();
  return std::unique_ptr<CoordinatorAssets>(
      new CoordinatorAssets(*std::move(store), max_asset_bytes));
}

std::vector<std::string> CoordinatorAssets::FindMissing(
    const std::vector<std::string>& sha256) const {
  std::vector<std::string> missing;
  for (const std::string& h : sha256) {
    if (!store_->Has(h)) missing.push_back(h);
  }
  return missing;
}

absl::Status CoordinatorAssets::Put(const std::string& sha256, std::string_view bytes) {
  if (static_cast<int64_t>(bytes.size()) > max_asset_bytes_) {
    return absl::ResourceExhaustedError(absl::StrCat(
        "asset ", sha256, ": ", bytes.size(), " bytes, above the limit of ", max_asset_bytes_));
  }
  if (absl::Status s = DecodeMeshAsset(bytes, absl::StrCat("asset ", sha256)).status(); !s.ok()) {
    return s;
  }
  return store_->Put(sha256, bytes);
}

absl::StatusOr<std::string> CoordinatorAssets::Get(const std::string& sha256) const {
  if (!IsSha256Hex(sha256)) {
    return absl::InvalidArgumentError("sha256: must be 64 lowercase hex characters");
  }
  return store_->Get(sha256);
}

MeshAssetResolver CoordinatorAssets::Resolver(int64_t max_triangles, int64_t* triangles) const {
  return
      [this, max_triangles, triangles](const std::string& sha256,
                                       const std::string& context) -> absl::StatusOr<MeshFileData> {
        absl::StatusOr<std::string> blob = store_->Get(sha256);
        if (absl::IsNotFound(blob.status())) {
          return absl::FailedPreconditionError(
              absl::StrCat(context, ": asset ", sha256, " has not been uploaded"));
        }
        if (!blob.ok()) return blob.status();
        absl::StatusOr<MeshFileData> mesh = DecodeMeshAsset(*blob, context);
        if (!mesh.ok()) return mesh.status();
        *triangles += static_cast<int64_t>(mesh->indices.size() / 3);
        if (max_triangles > 0 && *triangles > max_triangles) {
          return absl::ResourceExhaustedError(
              absl::StrCat(context, ": the scene exceeds this coordinator's limit of ",
                           max_triangles, " triangles"));
        }
        return mesh;
      };
}

}  // namespace pdsm
