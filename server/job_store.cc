#include "server/job_store.h"

#include <algorithm>

#include <sqlite3.h>

#include <filesystem>
#include <system_error>
#include <utility>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/string_view.h"
#include "spdlog/spdlog.h"

namespace pdsm {
namespace {

constexpr int kBusyTimeoutMs = 10'000;

// Schema version 1. Jobs are never deleted; `sequence` is AUTOINCREMENT so that it only grows.
constexpr char kSchemaV1[] = R"sql(
CREATE TABLE jobs (
  sequence INTEGER PRIMARY KEY AUTOINCREMENT,
  job_id TEXT NOT NULL UNIQUE,
  idempotency_key TEXT NOT NULL UNIQUE,
  scene_name TEXT NOT NULL,
  state INTEGER NOT NULL,
  priority INTEGER NOT NULL,
  error TEXT NOT NULL,
  tiles_total INTEGER NOT NULL,
  samples_total INTEGER NOT NULL,
  tile_assemblies INTEGER NOT NULL,
  created_unix_ms INTEGER NOT NULL,
  updated_unix_ms INTEGER NOT NULL,
  pdsm_bytes INTEGER NOT NULL,
  width INTEGER NOT NULL,
  height INTEGER NOT NULL,
  samples INTEGER NOT NULL,
  scene BLOB NOT NULL
);
CREATE INDEX jobs_by_state ON jobs (state, sequence);
CREATE TABLE done_tiles (
  job_id TEXT NOT NULL REFERENCES jobs (job_id),
  tile_index INTEGER NOT NULL,
  done_unix_ms INTEGER NOT NULL,
  PRIMARY KEY (job_id, tile_index)
) WITHOUT ROWID;
PRAGMA user_version = 1;
)sql";

// Version 2 (2026-12-03, issue #12 item 5): a done tile may be all lit (no shadow reaches its
// rays), stored as this flag alone and made again from the plan, not as a file.
constexpr char kSchemaV2[] = R"sql(
ALTER TABLE done_tiles ADD COLUMN all_lit INTEGER NOT NULL DEFAULT 0;
PRAGMA user_version = 2;
)sql";

// Version 3 (2026-12-06, issue #11): each job counts its done tiles, kept in step with
// done_tiles by the statements that add and remove rows. Reading a job's progress was a
// COUNT(*) over its done tiles, at every GetJob and every watcher's poll (10 a second): a
// B-tree walk over up to 2^18 rows each time, a fifth of the coordinator's CPU on a sparse
// 32768^2 world.
constexpr char kSchemaV3[] = R"sql(
ALTER TABLE jobs ADD COLUMN tiles_done INTEGER NOT NULL DEFAULT 0;
UPDATE jobs SET tiles_done = (SELECT COUNT(*) FROM done_tiles AS d WHERE d.job_id = jobs.job_id);
PRAGMA user_version = 3;
)sql";

// The columns ReadJob reads, in its order; the scene, when read, comes after them.
constexpr char kJobColumns[] =
    "job_id, idempotency_key, scene_name, state, priority, sequence, error, tiles_total, "
    "samples_total, tile_assemblies, tiles_done, created_unix_ms, "
    "updated_unix_ms, pdsm_bytes, width, height, samples";
constexpr int kSceneColumn = 17;

// SQLite's result code and message as a Status naming the database.
absl::Status SqliteError(int rc, sqlite3* db, const std::string& db_path,
                         absl::string_view action) {
  const std::string message =
      absl::StrFormat("%s: %s: %s (sqlite %d)", db_path, action,
                      db != nullptr ? sqlite3_errmsg(db) : sqlite3_errstr(rc), rc);
  switch (rc & 0xff) {
    case SQLITE_BUSY:
    case SQLITE_LOCKED:
    case SQLITE_CANTOPEN:
      return absl::UnavailableError(message);
    case SQLITE_FULL:
      return absl::ResourceExhaustedError(message);
    case SQLITE_CORRUPT:
    case SQLITE_NOTADB:
      return absl::DataLossError(message);
    case SQLITE_CONSTRAINT:
      return absl::AlreadyExistsError(message);
    default:
      return absl::InternalError(message);
  }
}

// A prepared statement, finalized at destruction. Text and blobs are bound without copying:
// REQUIRES that they outlive the statement's last Step().
class Statement {
 public:
  static absl::StatusOr<Statement> Prepare(sqlite3* db, const std::string& db_path,
                                           absl::string_view sql) {
    sqlite3_stmt* stmt = nullptr;
    const int rc = sqlite3_prepare_v2(db, sql.data(), static_cast<int>(sql.size()), &stmt, nullptr);
    if (rc != SQLITE_OK) {
      sqlite3_finalize(stmt);
      return SqliteError(rc, db, db_path, absl::StrCat("cannot prepare \"", sql, "\""));
    }
    return Statement(db, db_path, stmt);
  }

  Statement(Statement&& other) noexcept
      : db_(other.db_),
        db_path_(other.db_path_),
        stmt_(std::exchange(other.stmt_, nullptr)),
        bind_rc_(other.bind_rc_) {}
  Statement& operator=(Statement&&) = delete;
  ~Statement() { sqlite3_finalize(stmt_); }

  // Parameters are numbered from 1. A failed bind is reported by the next Step().
  void BindInt64(int i, int64_t v) { Check(sqlite3_bind_int64(stmt_, i, v)); }
  void BindText(int i, absl::string_view v) {
    Check(sqlite3_bind_text64(stmt_, i, v.empty() ? "" : v.data(), v.size(), SQLITE_STATIC,
                              SQLITE_UTF8));
  }
  void BindBlob(int i, absl::string_view v) {
    // A null pointer would bind NULL; an empty blob is a zero-length blob.
    Check(v.empty() ? sqlite3_bind_zeroblob(stmt_, i, 0)
                    : sqlite3_bind_blob64(stmt_, i, v.data(), v.size(), SQLITE_STATIC));
  }

  // True with a row to read, false when done.
  absl::StatusOr<bool> Step() {
    if (bind_rc_ != SQLITE_OK) {
      return SqliteError(bind_rc_, db_, *db_path_,
                         absl::StrCat("cannot bind parameters of \"", sqlite3_sql(stmt_), "\""));
    }
    const int rc = sqlite3_step(stmt_);
    if (rc == SQLITE_ROW) return true;
    if (rc == SQLITE_DONE) return false;
    return SqliteError(rc, db_, *db_path_, absl::StrCat("\"", sqlite3_sql(stmt_), "\" failed"));
  }

  // Steps a statement that returns no rows.
  absl::Status Run() {
    absl::StatusOr<bool> row = Step();
    if (!row.ok()) return row.status();
    return absl::OkStatus();
  }

  // Ends the current execution, so that it holds no locks (e.g. after reading one row).
  void Reset() { sqlite3_reset(stmt_); }

  int64_t Int64(int column) const { return sqlite3_column_int64(stmt_, column); }
  std::string Text(int column) const {
    const auto* text = reinterpret_cast<const char*>(sqlite3_column_text(stmt_, column));
    return text == nullptr ? std::string() : std::string(text, sqlite3_column_bytes(stmt_, column));
  }
  std::string Blob(int column) const {
    const auto* blob = static_cast<const char*>(sqlite3_column_blob(stmt_, column));
    return blob == nullptr ? std::string() : std::string(blob, sqlite3_column_bytes(stmt_, column));
  }

 private:
  Statement(sqlite3* db, const std::string& db_path, sqlite3_stmt* stmt)
      : db_(db), db_path_(&db_path), stmt_(stmt) {}

  void Check(int rc) {
    if (rc != SQLITE_OK && bind_rc_ == SQLITE_OK) bind_rc_ = rc;
  }

  sqlite3* db_;
  const std::string* db_path_;
  sqlite3_stmt* stmt_;
  int bind_rc_ = SQLITE_OK;
};

// Runs SQL without parameters or results (constants of this file only).
absl::Status Exec(sqlite3* db, const std::string& db_path, const char* sql) {
  const int rc = sqlite3_exec(db, sql, nullptr, nullptr, nullptr);
  if (rc != SQLITE_OK) return SqliteError(rc, db, db_path, absl::StrCat("\"", sql, "\" failed"));
  return absl::OkStatus();
}

// A write transaction, rolled back at destruction unless committed. IMMEDIATE takes the write
// lock at once (waiting up to the busy timeout), so that a read-then-write cannot deadlock
// with another writer.
class Transaction {
 public:
  Transaction(sqlite3* db, const std::string& db_path) : db_(db), db_path_(db_path) {}
  ~Transaction() {
    if (active_) sqlite3_exec(db_, "ROLLBACK", nullptr, nullptr, nullptr);
  }
  Transaction(const Transaction&) = delete;
  Transaction& operator=(const Transaction&) = delete;

  absl::Status Begin() {
    if (absl::Status s = Exec(db_, db_path_, "BEGIN IMMEDIATE"); !s.ok()) return s;
    active_ = true;
    return absl::OkStatus();
  }
  absl::Status Commit() {
    if (absl::Status s = Exec(db_, db_path_, "COMMIT"); !s.ok()) return s;
    active_ = false;
    return absl::OkStatus();
  }

 private:
  sqlite3* db_;
  const std::string& db_path_;
  bool active_ = false;
};

// REQUIRES: the statement selected kJobColumns, then the scene if with_scene.
JobRecord ReadJob(const Statement& row, bool with_scene) {
  JobRecord job;
  job.job_id = row.Text(0);
  job.idempotency_key = row.Text(1);
  job.scene_name = row.Text(2);
  const int64_t state = row.Int64(3);
  job.state = pdsm::v1::JobState_IsValid(static_cast<int>(state))
                  ? static_cast<pdsm::v1::JobState>(state)
                  : pdsm::v1::JOB_STATE_UNSPECIFIED;
  job.priority = static_cast<int>(row.Int64(4));
  job.sequence = row.Int64(5);
  job.error = row.Text(6);
  job.tiles_total = static_cast<int>(row.Int64(7));
  job.samples_total = row.Int64(8);
  job.tile_assemblies = static_cast<int>(row.Int64(9));
  job.tiles_done = static_cast<int>(row.Int64(10));
  job.created_unix_ms = row.Int64(11);
  job.updated_unix_ms = row.Int64(12);
  job.pdsm_bytes = static_cast<uint64_t>(row.Int64(13));
  job.width = static_cast<int>(row.Int64(14));
  job.height = static_cast<int>(row.Int64(15));
  job.samples = static_cast<int>(row.Int64(16));
  if (with_scene) job.scene = row.Blob(kSceneColumn);
  return job;
}

// Steps `stmt` to the end, reading every row as a job.
absl::StatusOr<std::vector<JobRecord>> ReadJobs(Statement& stmt, bool with_scene) {
  std::vector<JobRecord> jobs;
  while (true) {
    absl::StatusOr<bool> row = stmt.Step();
    if (!row.ok()) return row.status();
    if (!*row) return jobs;
    jobs.push_back(ReadJob(stmt, with_scene));
  }
}

absl::Status NoSuchJob(const std::string& job_id) {
  return absl::NotFoundError(absl::StrCat("no job ", job_id));
}

// Creates the schema in an empty database; FAILED_PRECONDITION for a newer one.
absl::Status Migrate(sqlite3* db, const std::string& db_path) {
  Transaction txn(db, db_path);
  if (absl::Status s = txn.Begin(); !s.ok()) return s;
  absl::StatusOr<Statement> stmt = Statement::Prepare(db, db_path, "PRAGMA user_version");
  if (!stmt.ok()) return stmt.status();
  absl::StatusOr<bool> row = stmt->Step();
  if (!row.ok()) return row.status();
  const int64_t version = *row ? stmt->Int64(0) : 0;
  stmt->Reset();
  if (version > JobStore::kSchemaVersion) {
    return absl::FailedPreconditionError(absl::StrFormat(
        "%s: schema version %d is newer than this build reads (%d); use a newer coordinator",
        db_path, version, JobStore::kSchemaVersion));
  }
  if (version < 0) {
    return absl::DataLossError(absl::StrFormat("%s: invalid schema version %d", db_path, version));
  }
  if (version == 0) {
    if (absl::Status s = Exec(db, db_path, kSchemaV1); !s.ok()) return s;
    spdlog::info("created job database {}", db_path);
  }
  if (version <= 1) {
    if (absl::Status s = Exec(db, db_path, kSchemaV2); !s.ok()) return s;
  }
  if (version <= 2) {
    if (absl::Status s = Exec(db, db_path, kSchemaV3); !s.ok()) return s;
  }
  if (version >= 1 && version < JobStore::kSchemaVersion) {
    spdlog::info("job database {}: schema version {} -> {}", db_path, version,
                 JobStore::kSchemaVersion);
  }
  return txn.Commit();
}

// WAL: readers do not block the writer, and a commit is one append and sync of the log.
absl::Status SetWalMode(sqlite3* db, const std::string& db_path) {
  absl::StatusOr<Statement> stmt = Statement::Prepare(db, db_path, "PRAGMA journal_mode=WAL");
  if (!stmt.ok()) return stmt.status();
  absl::StatusOr<bool> row = stmt->Step();
  if (!row.ok()) return row.status();
  const std::string mode = *row ? stmt->Text(0) : std::string();
  if (mode != "wal") {
    return absl::InternalError(
        absl::StrCat(db_path, ": cannot switch to WAL journal mode (got \"", mode, "\")"));
  }
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<std::unique_ptr<JobStore>> JobStore::Open(const std::string& data_dir) {
  std::error_code ec;
  std::filesystem::create_directories(data_dir, ec);
  if (ec) {
    return absl::UnavailableError(
        absl::StrCat("cannot create data folder ", data_dir, ": ", ec.message()));
  }
  std::string db_path = (std::filesystem::path(data_dir) / "jobs.db").string();
  sqlite3* db = nullptr;
  const int rc =
      sqlite3_open_v2(db_path.c_str(), &db,
                      SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_FULLMUTEX, nullptr);
  // The store owns the handle from here on, even when opening failed.
  std::unique_ptr<JobStore> store(new JobStore(db, std::move(db_path)));
  if (rc != SQLITE_OK) return SqliteError(rc, db, store->db_path_, "cannot open");
  sqlite3_extended_result_codes(db, 1);
  sqlite3_busy_timeout(db, kBusyTimeoutMs);

  if (absl::Status s = SetWalMode(db, store->db_path_); !s.ok()) return s;
  for (const char* pragma : {"PRAGMA synchronous=FULL", "PRAGMA foreign_keys=ON"}) {
    if (absl::Status s = Exec(db, store->db_path_, pragma); !s.ok()) return s;
  }
  if (absl::Status s = Migrate(db, store->db_path_); !s.ok()) return s;
  return store;
}

JobStore::~JobStore() { sqlite3_close_v2(db_); }

absl::StatusOr<JobRecord> JobStore::CreateJob(const JobRecord& record, bool* created) {
  if (record.job_id.empty() || record.idempotency_key.empty()) {
    return absl::InvalidArgumentError("CreateJob: job_id and idempotency_key must not be empty");
  }
  absl::MutexLock lock(&mu_);
  Transaction txn(db_, db_path_);
  if (absl::Status s = txn.Begin(); !s.ok()) return s;

  absl::StatusOr<Statement> find = Statement::Prepare(
      db_, db_path_,
      absl::StrCat("SELECT ", kJobColumns, ", scene", " FROM jobs WHERE idempotency_key = ?1"));
  if (!find.ok()) return find.status();
  find->BindText(1, record.idempotency_key);
  absl::StatusOr<bool> found = find->Step();
  if (!found.ok()) return found.status();
  if (*found) {
    JobRecord existing = ReadJob(*find, /*with_scene=*/true);
    find->Reset();
    if (absl::Status s = txn.Commit(); !s.ok()) return s;
    if (created != nullptr) *created = false;
    return existing;
  }

  absl::StatusOr<Statement> insert = Statement::Prepare(db_, db_path_, R"sql(
      INSERT INTO jobs (job_id, idempotency_key, scene_name, state, priority, error,
                        tiles_total, samples_total, tile_assemblies, created_unix_ms,
                        updated_unix_ms, pdsm_bytes, width, height, samples, scene)
      VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, 0, ?9, ?10, ?11, ?12, ?13, ?14, ?15))sql");
  if (!insert.ok()) return insert.status();
  insert->BindText(1, record.job_id);
  insert->BindText(2, record.idempotency_key);
  insert->BindText(3, record.scene_name);
  insert->BindInt64(4, record.state);
  insert->BindInt64(5, record.priority);
  insert->BindText(6, record.error);
  insert->BindInt64(7, record.tiles_total);
  insert->BindInt64(8, record.samples_total);
  insert->BindInt64(9, record.created_unix_ms);
  insert->BindInt64(10, record.updated_unix_ms);
  insert->BindInt64(11, static_cast<int64_t>(record.pdsm_bytes));
  insert->BindInt64(12, record.width);
  insert->BindInt64(13, record.height);
  insert->BindInt64(14, record.samples);
  insert->BindBlob(15, record.scene);
  if (absl::Status s = insert->Run(); !s.ok()) {
    if (s.code() == absl::StatusCode::kAlreadyExists) {
      return absl::AlreadyExistsError(absl::StrCat(
          "job ", record.job_id, " exists with another idempotency key (", s.message(), ")"));
    }
    return s;
  }
  const int64_t sequence = sqlite3_last_insert_rowid(db_);
  if (absl::Status s = txn.Commit(); !s.ok()) return s;

  JobRecord job = record;
  job.sequence = sequence;
  job.tile_assemblies = 0;
  job.tiles_done = 0;
  if (created != nullptr) *created = true;
  return job;
}

absl::StatusOr<JobRecord> JobStore::GetJob(const std::string& job_id) {
  absl::MutexLock lock(&mu_);
  absl::StatusOr<Statement> stmt = Statement::Prepare(
      db_, db_path_,
      absl::StrCat("SELECT ", kJobColumns, ", scene", " FROM jobs WHERE job_id = ?1"));
  if (!stmt.ok()) return stmt.status();
  stmt->BindText(1, job_id);
  absl::StatusOr<bool> row = stmt->Step();
  if (!row.ok()) return row.status();
  if (!*row) return NoSuchJob(job_id);
  return ReadJob(*stmt, /*with_scene=*/true);
}

absl::StatusOr<std::vector<JobRecord>> JobStore::ListJobs(int limit) {
  absl::MutexLock lock(&mu_);
  absl::StatusOr<Statement> stmt = Statement::Prepare(
      db_, db_path_,
      absl::StrCat("SELECT ", kJobColumns, " FROM jobs ORDER BY sequence DESC LIMIT ?1"));
  if (!stmt.ok()) return stmt.status();
  stmt->BindInt64(1, limit > 0 ? limit : -1);  // a negative LIMIT is no limit
  return ReadJobs(*stmt, /*with_scene=*/false);
}

absl::StatusOr<std::map<pdsm::v1::JobState, JobStore::StateTotals>> JobStore::TotalsByState() {
  absl::MutexLock lock(&mu_);
  absl::StatusOr<Statement> stmt = Statement::Prepare(
      db_, db_path_,
      "SELECT state, COUNT(*), COALESCE(SUM(pdsm_bytes), 0) FROM jobs GROUP BY state");
  if (!stmt.ok()) return stmt.status();
  std::map<pdsm::v1::JobState, StateTotals> totals;
  while (true) {
    absl::StatusOr<bool> row = stmt->Step();
    if (!row.ok()) return row.status();
    if (!*row) break;
    const int64_t state = stmt->Int64(0);
    if (!pdsm::v1::JobState_IsValid(static_cast<int>(state))) continue;
    StateTotals& t = totals[static_cast<pdsm::v1::JobState>(state)];
    t.jobs = stmt->Int64(1);
    t.pdsm_bytes = stmt->Int64(2);
  }
  return totals;
}

absl::StatusOr<std::vector<JobRecord>> JobStore::UnfinishedJobs() {
  absl::MutexLock lock(&mu_);
  absl::StatusOr<Statement> stmt =
      Statement::Prepare(db_, db_path_,
                         absl::StrCat("SELECT ", kJobColumns, ", scene",
                                      " FROM jobs WHERE state IN (?1, ?2) ORDER BY sequence ASC"));
  if (!stmt.ok()) return stmt.status();
  stmt->BindInt64(1, pdsm::v1::QUEUED);
  stmt->BindInt64(2, pdsm::v1::RUNNING);
  return ReadJobs(*stmt, /*with_scene=*/true);
}

absl::Status JobStore::SetState(const std::string& job_id, pdsm::v1::JobState state,
                                const std::string& error, int64_t now_ms) {
  if (!pdsm::v1::JobState_IsValid(state) || state == pdsm::v1::JOB_STATE_UNSPECIFIED) {
    return absl::InvalidArgumentError(
        absl::StrCat("SetState(", job_id, "): invalid state ", static_cast<int>(state)));
  }
  absl::MutexLock lock(&mu_);
  absl::StatusOr<Statement> stmt = Statement::Prepare(
      db_, db_path_,
      "UPDATE jobs SET state = ?1, error = ?2, updated_unix_ms = ?3 WHERE job_id = ?4");
  if (!stmt.ok()) return stmt.status();
  stmt->BindInt64(1, state);
  stmt->BindText(2, error);
  stmt->BindInt64(3, now_ms);
  stmt->BindText(4, job_id);
  if (absl::Status s = stmt->Run(); !s.ok()) return s;
  if (sqlite3_changes(db_) == 0) return NoSuchJob(job_id);
  return absl::OkStatus();
}

absl::Status JobStore::SetSucceeded(const std::string& job_id, uint64_t pdsm_bytes,
                                    int64_t now_ms) {
  absl::MutexLock lock(&mu_);
  absl::StatusOr<Statement> stmt = Statement::Prepare(db_, db_path_, R"sql(
      UPDATE jobs SET state = ?1, error = '', pdsm_bytes = ?2, updated_unix_ms = ?3
      WHERE job_id = ?4)sql");
  if (!stmt.ok()) return stmt.status();
  stmt->BindInt64(1, pdsm::v1::SUCCEEDED);
  stmt->BindInt64(2, static_cast<int64_t>(pdsm_bytes));
  stmt->BindInt64(3, now_ms);
  stmt->BindText(4, job_id);
  if (absl::Status s = stmt->Run(); !s.ok()) return s;
  if (sqlite3_changes(db_) == 0) return NoSuchJob(job_id);
  return absl::OkStatus();
}

absl::Status JobStore::MarkTileDone(const std::string& job_id, int tile_index, int64_t now_ms,
                                    bool all_lit) {
  return MarkTilesDone(job_id, {tile_index}, now_ms, all_lit);
}

absl::Status JobStore::MarkTilesDone(const std::string& job_id, const std::vector<int>& tiles,
                                     int64_t now_ms, bool all_lit) {
  absl::MutexLock lock(&mu_);
  Transaction txn(db_, db_path_);
  if (absl::Status s = txn.Begin(); !s.ok()) return s;

  absl::StatusOr<Statement> total =
      Statement::Prepare(db_, db_path_, "SELECT tiles_total FROM jobs WHERE job_id = ?1");
  if (!total.ok()) return total.status();
  total->BindText(1, job_id);
  absl::StatusOr<bool> row = total->Step();
  if (!row.ok()) return row.status();
  if (!*row) return NoSuchJob(job_id);
  const int64_t tiles_total = total->Int64(0);
  total->Reset();
  for (int tile_index : tiles) {
    if (tile_index < 0 || tile_index >= tiles_total) {
      return absl::InvalidArgumentError(
          absl::StrFormat("job %s: tile %d is outside [0, %d)", job_id, tile_index, tiles_total));
    }
  }

  // A tile done again updates its row: it may have been stored as a file and is all lit now,
  // or the other way round. Only new rows count towards tiles_done.
  absl::StatusOr<Statement> insert = Statement::Prepare(db_, db_path_, R"sql(
      INSERT OR IGNORE INTO done_tiles (job_id, tile_index, done_unix_ms, all_lit)
      VALUES (?1, ?2, ?3, ?4))sql");
  if (!insert.ok()) return insert.status();
  absl::StatusOr<Statement> update = Statement::Prepare(db_, db_path_, R"sql(
      UPDATE done_tiles SET done_unix_ms = ?3, all_lit = ?4
      WHERE job_id = ?1 AND tile_index = ?2)sql");
  if (!update.ok()) return update.status();
  int64_t added = 0;
  for (int tile_index : tiles) {
    insert->BindText(1, job_id);
    insert->BindInt64(2, tile_index);
    insert->BindInt64(3, now_ms);
    insert->BindInt64(4, all_lit ? 1 : 0);
    if (absl::Status s = insert->Run(); !s.ok()) return s;
    insert->Reset();
    if (sqlite3_changes(db_) == 1) {
      ++added;
      continue;
    }
    update->BindText(1, job_id);
    update->BindInt64(2, tile_index);
    update->BindInt64(3, now_ms);
    update->BindInt64(4, all_lit ? 1 : 0);
    if (absl::Status s = update->Run(); !s.ok()) return s;
    update->Reset();
  }

  absl::StatusOr<Statement> count = Statement::Prepare(db_, db_path_, R"sql(
      UPDATE jobs SET tile_assemblies = tile_assemblies + ?1, tiles_done = tiles_done + ?2,
                      updated_unix_ms = ?3
      WHERE job_id = ?4)sql");
  if (!count.ok()) return count.status();
  count->BindInt64(1, static_cast<int64_t>(tiles.size()));
  count->BindInt64(2, added);
  count->BindInt64(3, now_ms);
  count->BindText(4, job_id);
  if (absl::Status s = count->Run(); !s.ok()) return s;
  return txn.Commit();
}

absl::Status JobStore::CheckJobExists(const std::string& job_id) {
  absl::StatusOr<Statement> exists =
      Statement::Prepare(db_, db_path_, "SELECT 1 FROM jobs WHERE job_id = ?1");
  if (!exists.ok()) return exists.status();
  exists->BindText(1, job_id);
  absl::StatusOr<bool> found = exists->Step();
  if (!found.ok()) return found.status();
  if (!*found) return NoSuchJob(job_id);
  exists->Reset();
  return absl::OkStatus();
}

absl::Status JobStore::MarkTileUndone(const std::string& job_id, int tile_index) {
  absl::MutexLock lock(&mu_);
  Transaction txn(db_, db_path_);
  if (absl::Status s = txn.Begin(); !s.ok()) return s;
  if (absl::Status s = CheckJobExists(job_id); !s.ok()) return s;
  absl::StatusOr<Statement> remove = Statement::Prepare(
      db_, db_path_, "DELETE FROM done_tiles WHERE job_id = ?1 AND tile_index = ?2");
  if (!remove.ok()) return remove.status();
  remove->BindText(1, job_id);
  remove->BindInt64(2, tile_index);
  if (absl::Status s = remove->Run(); !s.ok()) return s;
  if (sqlite3_changes(db_) == 1) {
    absl::StatusOr<Statement> count = Statement::Prepare(
        db_, db_path_, "UPDATE jobs SET tiles_done = tiles_done - 1 WHERE job_id = ?1");
    if (!count.ok()) return count.status();
    count->BindText(1, job_id);
    if (absl::Status s = count->Run(); !s.ok()) return s;
  }
  return txn.Commit();
}

absl::StatusOr<std::vector<int>> JobStore::DoneTiles(const std::string& job_id) {
  return SelectTiles(job_id, "");
}

absl::StatusOr<std::vector<int>> JobStore::AllLitTiles(const std::string& job_id) {
  return SelectTiles(job_id, " AND all_lit = 1");
}

absl::StatusOr<std::vector<int>> JobStore::SelectTiles(const std::string& job_id,
                                                       absl::string_view condition) {
  absl::MutexLock lock(&mu_);
  if (absl::Status s = CheckJobExists(job_id); !s.ok()) return s;

  absl::StatusOr<Statement> stmt =
      Statement::Prepare(db_, db_path_,
                         absl::StrCat("SELECT tile_index FROM done_tiles WHERE job_id = ?1",
                                      condition, " ORDER BY tile_index ASC"));
  if (!stmt.ok()) return stmt.status();
  stmt->BindText(1, job_id);
  std::vector<int> tiles;
  while (true) {
    absl::StatusOr<bool> row = stmt->Step();
    if (!row.ok()) return row.status();
    if (!*row) return tiles;
    tiles.push_back(static_cast<int>(stmt->Int64(0)));
  }
}

}  // namespace pdsm
