// The coordinator's durable job state: one SQLite database, DATA_DIR/jobs.db, holding every
// job and the tiles of each that are finished and stored on disk (tile_file.h). After a crash
// (kill -9) and a restart on the same folder, UnfinishedJobs() and DoneTiles() say what to
// resume and which tiles not to recompute. Every change is one transaction, synced to the disk
// (WAL, synchronous=FULL) before the call returns.
#ifndef PDSM_SERVER_JOB_STORE_H_
#define PDSM_SERVER_JOB_STORE_H_

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "absl/base/thread_annotations.h"
#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "absl/synchronization/mutex.h"
#include "pdsm/v1/jobs.pb.h"

struct sqlite3;

namespace pdsm {

struct JobRecord {
  std::string job_id;  // 16 lowercase hex
  std::string idempotency_key;
  std::string scene_name;
  pdsm::v1::JobState state = pdsm::v1::QUEUED;
  int priority = 0;
  int64_t sequence = 0;  // assigned by CreateJob: submission order (monotonic)
  std::string error;
  int tiles_total = 0;
  int64_t samples_total = 0;
  int tile_assemblies = 0;  // maintained by MarkTileDone
  int tiles_done = 0;       // count of done tile rows (filled on read)
  int64_t created_unix_ms = 0, updated_unix_ms = 0;
  uint64_t pdsm_bytes = 0;
  int width = 0, height = 0, samples = 0;
  std::string scene;  // serialized pdsm.v1.Scene (BLOB)
};

// Thread-safe: one connection, every call under an internal mutex. Errors carry SQLite's
// message and the database's path; their codes: UNAVAILABLE (database busy or locked by
// another process past the busy timeout, or cannot be opened), RESOURCE_EXHAUSTED (disk full),
// DATA_LOSS (corrupt database), INTERNAL (anything else).
class JobStore {
 public:
  // The database's schema version (PRAGMA user_version).
  // 2 since 2026-12-03 (done tiles flagged all lit), 3 since 2026-12-06 (each job counts its
  // done tiles); an older database is upgraded in place when opened (and is then no longer
  // readable by older builds).
  static constexpr int kSchemaVersion = 3;

  // Opens or creates DATA_DIR/jobs.db, creating DATA_DIR (and its parents) if needed.
  // FAILED_PRECONDITION when the database's schema is newer than kSchemaVersion (written by a
  // newer build).
  static absl::StatusOr<std::unique_ptr<JobStore>> Open(const std::string& data_dir);
  ~JobStore();
  JobStore(const JobStore&) = delete;
  JobStore& operator=(const JobStore&) = delete;

  // Inserts `record` with the next sequence number, or, if a job with the same
  // idempotency_key exists, returns that one unchanged (whatever `record` holds). `*created`
  // (if not null) tells which. record.sequence, tile_assemblies and tiles_done are ignored
  // (a new job starts with none); every other field is stored as given.
  // ALREADY_EXISTS when another job (other idempotency key) has the same job_id;
  // INVALID_ARGUMENT when job_id or idempotency_key is empty.
  absl::StatusOr<JobRecord> CreateJob(const JobRecord& record, bool* created);

  // The job, scene included. NOT_FOUND when there is none.
  absl::StatusOr<JobRecord> GetJob(const std::string& job_id);

  // At most `limit` jobs (all when limit <= 0), newest first (sequence descending), with
  // `scene` left empty.
  absl::StatusOr<std::vector<JobRecord>> ListJobs(int limit);

  // Per state: how many jobs, and the bytes of their PDSMs (non-zero for SUCCEEDED only). For
  // metrics: one aggregate query, no rows read into memory.
  struct StateTotals {
    int64_t jobs = 0;
    int64_t pdsm_bytes = 0;
  };
  absl::StatusOr<std::map<pdsm::v1::JobState, StateTotals>> TotalsByState();

  // The jobs to resume: QUEUED or RUNNING, in submission order (sequence ascending), scenes
  // included.
  absl::StatusOr<std::vector<JobRecord>> UnfinishedJobs();

  // Sets the state and error and stamps updated_unix_ms = now_ms. NOT_FOUND when there is no
  // such job; INVALID_ARGUMENT for JOB_STATE_UNSPECIFIED or a value outside the enum.
  absl::Status SetState(const std::string& job_id, pdsm::v1::JobState state,
                        const std::string& error, int64_t now_ms);

  // SUCCEEDED, with the PDSM's size and no error. NOT_FOUND when there is no such job.
  absl::Status SetSucceeded(const std::string& job_id, uint64_t pdsm_bytes, int64_t now_ms);

  // Records tile `tile_index` of the job as finished and stored: one transaction that adds the
  // tile to the job's done tiles (no-op if there) and increments tile_assemblies, even when
  // the tile was done already (that counts a recomputation, which tests detect). Stamps
  // updated_unix_ms. NOT_FOUND when there is no such job; INVALID_ARGUMENT when tile_index is
  // outside [0, tiles_total). `all_lit`: the tile is stored as this flag alone, not as a file
  // (server/stored_job.h); a tile marked again takes the new flag.
  absl::Status MarkTileDone(const std::string& job_id, int tile_index, int64_t now_ms,
                            bool all_lit = false);
  // MarkTileDone of every tile in one transaction (one sync for thousands of tiles no caster
  // reaches); nothing is marked when one is outside the job.
  absl::Status MarkTilesDone(const std::string& job_id, const std::vector<int>& tiles,
                             int64_t now_ms, bool all_lit = false);

  // Takes tile `tile_index` out of the job's done tiles (no-op if not there): verification found
  // it computed from a quarantined worker's results, so a resumed job must redo it.
  // tile_assemblies is unchanged (the redo counts when it is marked done again). NOT_FOUND when
  // there is no such job.
  absl::Status MarkTileUndone(const std::string& job_id, int tile_index);

  // The job's done tiles, ascending. NOT_FOUND when there is no such job.
  absl::StatusOr<std::vector<int>> DoneTiles(const std::string& job_id);
  // Those of the job's done tiles marked all lit, ascending. NOT_FOUND when there is no such job.
  absl::StatusOr<std::vector<int>> AllLitTiles(const std::string& job_id);

  const std::string& db_path() const { return db_path_; }

 private:
  JobStore(sqlite3* db, std::string db_path) : db_(db), db_path_(std::move(db_path)) {}
  // NOT_FOUND (NoSuchJob) unless the job has a row.
  absl::Status CheckJobExists(const std::string& job_id) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_);
  // The job's done tiles whose row meets `condition` (SQL after "WHERE job_id = ?1", "" for
  // all), ascending.
  absl::StatusOr<std::vector<int>> SelectTiles(const std::string& job_id,
                                               absl::string_view condition);

  absl::Mutex mu_;
  sqlite3* const db_ ABSL_PT_GUARDED_BY(mu_);  // closed by the destructor
  const std::string db_path_;
};

}  // namespace pdsm

#endif  // PDSM_SERVER_JOB_STORE_H_
