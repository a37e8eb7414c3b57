// The coordinator's mesh assets: SHA-256-addressed blobs clients upload (core/assets) and
// workers fetch. Blobs that are not meshes are refused at upload, not when a job needs them.
#ifndef PDSM_SERVER_COORDINATOR_ASSETS_H_
#define PDSM_SERVER_COORDINATOR_ASSETS_H_

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/statusor.h"
#include "core/assets/asset_store.h"
#include "core/scene/scene_loader.h"

namespace pdsm {

// Thread-safe (AssetStore is).
class CoordinatorAssets {
 public:
  // Opens or creates the store in `dir`.
  static absl::StatusOr<std::unique_ptr<CoordinatorAssets>> Open(const std::string& dir,
                                                                 int64_t max_asset_bytes,
                                                                 FileSystem* fs = nullptr);

  int64_t max_asset_bytes() const { return max_asset_bytes_; }
  // The hashes of `sha256` not stored yet, in order.
  std::vector<std::string> FindMissing(const std::vector<std::string>& sha256) const;
  // Stores a complete blob. INVALID_ARGUMENT (bad hash, not a mesh), RESOURCE_EXHAUSTED (size).
  absl::Status Put(const std::string& sha256, std::string_view bytes);
  // INVALID_ARGUMENT for a malformed hash, NOT_FOUND when absent.
  absl::StatusOr<std::string> Get(const std::string& sha256) const;

  // Decodes a job's meshes from the store. With `max_triangles` > 0 it counts their triangles
  // into *triangles as they decode and stops with RESOURCE_EXHAUSTED past the limit, so a huge
  // scene costs little. FAILED_PRECONDITION for an asset never uploaded.
  // REQUIRES: `triangles` outlives the resolver.
  MeshAssetResolver Resolver(int64_t max_triangles, int64_t* triangles) const;

 private:
  CoordinatorAssets(std::unique_ptr<AssetStore> store, int64_t max_asset_bytes)
      : store_(std::move(store)), max_asset_bytes_(max_asset_bytes) {}

  const std::unique_ptr<AssetStore> store_;
  const int64_t max_asset_bytes_;
};

}  // namespace pdsm

#endif  // PDSM_SERVER_COORDINATOR_ASSETS_H_
