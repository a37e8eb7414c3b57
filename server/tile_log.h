// A running job's finished tiles on the coordinator's disk, in one file: DATA_DIR/jobs/<id>/
// tiles.log. Each tile is appended as a record when it is assembled and is durable after the
// next Sync, which the job calls once per finished stage of a tile group, before the job store
// marks that stage's tiles done (server/stored_job.h). So a restart finds every tile the store
// calls done, and a job costs one sync per group, not a new file and three syncs per tile (a
// third of the coordinator's CPU on a sparse world).
//
// Layout, all integers little-endian:
//   char[8]  magic "PDSMTLOG"
//   uint32   version (kTileLogVersion)
//   uint32   0
// then records, one after the other:
//   uint32   magic "TREC"
//   int32    tile: its index among the job's tiles (server/job_lights.h)
//   uint64   payload bytes
//   uint64   FNV-1a 64 of the 16 bytes above
//   char     payload[]: the tile as a tile file (core/pipeline/tile_file.h, which checksums it)
// A tile stored again is appended again; the last record of a tile is the tile. A crash during
// an append leaves a torn record at the end, which Open cuts off: appends are never made after
// bytes that are not whole records.
//
// Thread-safe.
#ifndef PDSM_SERVER_TILE_LOG_H_
#define PDSM_SERVER_TILE_LOG_H_

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "absl/base/thread_annotations.h"
#include "absl/container/flat_hash_map.h"
#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/synchronization/mutex.h"
#include "core/util/file_system.h"

namespace pdsm {

inline constexpr uint32_t kTileLogVersion = 1;

class TileLog {
 public:
  // Opens the log at `path`, creating it (and making its name durable) when there is none,
  // and reads every record: each record's frame and its tile file's checksum are checked. A
  // tail that is not whole records (a crash during an append, or damage) is cut off, with a
  // warning naming the file and the bytes dropped; the tiles it held are then not in the log.
  // Errors: the file system's; DATA_LOSS naming the file when it is not a tile log;
  // FAILED_PRECONDITION for a version newer than this build reads. `fs` null: the real one.
  static absl::StatusOr<std::unique_ptr<TileLog>> Open(const std::string& path,
                                                       FileSystem* fs = nullptr);

  // Appends tile `tile`'s file bytes (EncodeTileFile), not durable before Sync. A failed
  // append is cut off again; if that fails too, every later append and sync fails (the log
  // would hold bytes no reader can pass), and so does the job.
  absl::Status Append(int tile, const std::string& tile_file);
  // Makes every record appended so far durable (fdatasync).
  absl::Status Sync();

  // The tile's last record's bytes (a tile file). NOT_FOUND when the log holds none (or it was
  // forgotten); DATA_LOSS naming the file when reading it back fails.
  absl::StatusOr<std::string> Read(int tile) const;
  bool Has(int tile) const;
  // The log's records of `tile` no longer count (the tile was withdrawn, or is stored all
  // lit): Read is NOT_FOUND until it is appended again. In memory only: reopened, the log has
  // the tile again, and the job store decides (its row, its all-lit flag).
  void Forget(int tile);
  // Tiles with a record, ascending.
  std::vector<int> Tiles() const;

  const std::string& path() const { return file_->path(); }

 private:
  struct Record {
    uint64_t offset = 0;  // of the payload
    uint64_t bytes = 0;
  };
  explicit TileLog(std::unique_ptr<RandomAccessFile> file) : file_(std::move(file)) {}
  // Reads the records from the header's end; cuts off what is not whole records.
  absl::Status Load(uint64_t size);

  const std::unique_ptr<RandomAccessFile> file_;
  mutable absl::Mutex mu_;
  uint64_t end_ ABSL_GUARDED_BY(mu_) = 0;  // where the next record goes
  absl::Status broken_ ABSL_GUARDED_BY(mu_);
  absl::flat_hash_map<int, Record> records_ ABSL_GUARDED_BY(mu_);
};

}  // namespace pdsm

#endif  // PDSM_SERVER_TILE_LOG_H_
