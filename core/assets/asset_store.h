// A content-addressed folder of blobs (mesh assets): the blob whose SHA-256 is <sha> lives at
// <dir>/<sha[0:2]>/<sha>. Names come only from validated hashes, never from client paths.
#ifndef PDSM_CORE_ASSETS_ASSET_STORE_H_
#define PDSM_CORE_ASSETS_ASSET_STORE_H_

#include <memory>
#include <string>
#include <string_view>
#include <utility>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/util/file_system.h"

namespace pdsm {

// Thread-safe, and safe to share one folder between processes: every operation is atomic on
// the filesystem (a blob is written by WriteFileAtomically, core/util/atomic_file.h: a unique
// temporary name, synced, renamed into place, the folder synced), and the object holds no
// mutable state. Temporary files are named "<sha>.tmp-XXXXXX" in the blob's folder (never a
// valid hash, so never read as a blob); a crash can leave one behind, never a partial blob
// under its final name.
class AssetStore {
 public:
  // Creates `dir` (and its parents) if needed. Errors: the errno's code when it cannot be
  // created, FAILED_PRECONDITION when it exists and is not a folder. Blobs are written through
  // `fs` (null: FileSystem::Default()), which must outlive the store.
  static absl::StatusOr<std::unique_ptr<AssetStore>> Open(const std::string& dir,
                                                          FileSystem* fs = nullptr);

  // Whether a blob is stored under `sha256` (false for a malformed hash). Does not read it.
  bool Has(const std::string& sha256) const;

  // Stores `bytes` under `sha256`; storing a blob that is already there rewrites it (the same
  // bytes) atomically. Errors: INVALID_ARGUMENT when `sha256` is not IsSha256Hex or the bytes
  // hash differently ("asset <sha>: content hashes to <other>"); the errno's code on I/O
  // failure (nothing is left at the final name then).
  absl::Status Put(const std::string& sha256, std::string_view bytes);

  // The blob stored under `sha256`, its hash verified. Errors: INVALID_ARGUMENT for a malformed
  // hash, NOT_FOUND when absent, DATA_LOSS when the stored bytes hash differently (the corrupt
  // file is removed, so a new upload can replace it), the errno's code on I/O failure.
  absl::StatusOr<std::string> Get(const std::string& sha256) const;

  // <dir>/<sha256[0:2]>/<sha256>. REQUIRES: IsSha256Hex(sha256).
  std::string PathFor(const std::string& sha256) const;

  const std::string& dir() const { return dir_; }

 private:
  AssetStore(std::string dir, FileSystem* fs) : dir_(std::move(dir)), fs_(fs) {}

  std::string dir_;
  FileSystem* fs_;
};

}  // namespace pdsm

#endif  // PDSM_CORE_ASSETS_ASSET_STORE_H_
