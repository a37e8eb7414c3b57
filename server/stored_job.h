// A coordinator's job while it runs, and where its results go: one JobOutput
// (core/pipeline/bake_engine.h) per light of the job (server/job_lights.h), each its light's
// engine job's. Under DATA_DIR/jobs/<id>/:
//   tiles.log           each finished tile (server/tile_log.h) by its index among the job's
//                       tiles, appended as it is stored; at the end of each stage of a group
//                       (JobOutput::CommitTiles) the log is synced, then the stage's tiles get
//                       their rows in the job store (MarkTilesDone), so a restart resumes the
//                       job with only its missing tiles. A tile found all lit (what the plan
//                       alone makes again) has no record, its row says so (all_lit);
//   pdsm.exr            the PDSM, written from the log when every light's tiles are stored:
//                       for one light the single-part file, for several the multipart file
//                       the local bake writes (PdsmLightsWriter), byte for byte.
// A light with bake.maxRefinement > 1 (adaptive resolution, docs/algorithms.md section 10)
// has a second engine job once its base tiles are all stored: the coordinator chooses the
// pixels to refine from them (SelectRefinedPixels), plans the level (RefinementHooks) and
// runs it as LevelEngineJobId of the light's engine job; its tiles are kept beside the
// file (a scratch file, not the log: a restart chooses and bakes the level again, the same
// pixels from the same base tiles), and when it is finished its sub-pixel functions are
// spliced into the base tiles (SpliceRefinedTiles), which the file is then written with. The
// log keeps the base tiles unspliced. The light ends when its last engine job ends.
// Builds before 2026-12-06 kept a file per tile (tiles/<index>.tile); a job resumed from
// them takes their tiles into its log first (ResumeTiles).
// The job's states (RUNNING, SUCCEEDED, FAILED, CANCELLED) go to the job store as they come.
// The job ends when every light's engine job has ended: SUCCEEDED when all succeeded, else
// as the first that did not (a light that fails ends the others through `end_lights`).
//
// Thread-safe: the engine calls the JobOutput methods from its executor, the coordinator the
// accessors from its gRPC threads.
#ifndef PDSM_SERVER_STORED_JOB_H_
#define PDSM_SERVER_STORED_JOB_H_

#include <atomic>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "absl/base/thread_annotations.h"
#include "absl/status/statusor.h"
#include "absl/synchronization/mutex.h"
#include "core/bake/bake_plan.h"
#include "core/bake/refined_pixels.h"
#include "core/pdsm/tile_chunk.h"
#include "core/pipeline/bake_engine.h"
#include "core/util/file_system.h"
#include "pdsm/v1/scene.pb.h"
#include "server/job_lights.h"
#include "server/job_store.h"
#include "server/tile_log.h"

namespace pdsm {

// Where a job's files are.
struct JobPaths {
  JobPaths(const std::string& data_dir, const std::string& job_id);
  std::string dir;   // DATA_DIR/jobs/<id>
  std::string log;   // its tiles.log
  std::string pdsm;  // its pdsm.exr
  // The folder of a file per tile that earlier builds kept, and a tile's file there.
  std::string tiles;
  std::string Tile(int tile_index) const;
};

// How a job starts its lights' refinement levels: the coordinator's.
struct RefinementHooks {
  // The level's plan of light `light` (its index in the job) for `refined`, as PlanJobLights
  // plans a light (server/job_admission.h, PlanJobLightLevel).
  std::function<absl::StatusOr<PlannedLight>(int light, std::shared_ptr<const RefinedPixels>)>
      plan_level;
  // Adds the level's engine job `engine_id`, of `plan`, storing into `output`.
  std::function<absl::Status(const std::string& engine_id, std::shared_ptr<const BakePlan> plan,
                             std::shared_ptr<JobOutput> output)>
      start_level;
  // The level holds `bytes` more in the coordinator until the job ends: its plan and refined
  // pixels when it starts, its spliced tiles when it ends (counted against --max-planned-mib,
  // server/plan_budget.h). Optional.
  std::function<void(int64_t bytes)> hold;
  int threads = 1;  // choosing and splicing the refined pixels
};

class StoredJob : public std::enable_shared_from_this<StoredJob> {
 public:
  // Made with std::make_shared (LightOutput). `store` outlives this. `plans`: one per light, in
  // scene order. `on_ended(job_id)` runs at the end of the job's end. `end_lights(status)` ends the
  // engine jobs of the job's other lights (kFailed with `status`) when one light failed; it is
  // called without any lock of this held. `fs`: where tile files and the PDSM are written (null:
  // the real file system). `refinement`: how a refined light's level starts (without hooks a
  // refined light's base finishes with an INTERNAL error).
  StoredJob(JobStore* store, const std::string& data_dir, JobRecord record, pdsm::v1::Scene scene,
            std::vector<PlannedLight> plans, std::function<void(const std::string&)> on_ended,
            std::function<void(const absl::Status&)> end_lights = nullptr, FileSystem* fs = nullptr,
            RefinementHooks refinement = {});
  ~StoredJob();

  const JobRecord& record() const { return record_; }  // as it was when the job was activated
  const pdsm::v1::Scene& scene() const { return scene_; }
  const std::vector<JobLight>& lights() const { return lights_; }
  // The first light's plan fingerprint (GetJobScene's; each task carries its own light's).
  const std::string& fingerprint() const { return lights_.front().fingerprint; }
  const JobPaths& paths() const { return paths_; }
  bool ended() const { return ended_; }

  // Where light `light`'s engine job stores its results; it holds this job. REQUIRES: this
  // is owned by a shared_ptr, light < lights().size().
  std::shared_ptr<JobOutput> LightOutput(int light);

  // Before the job's lights go to the engine: opens the tile log (creating it; taking in the
  // tile files of an earlier build), and returns those of `done_tiles` (the store's, job
  // indices, ascending) that the job really has: a done tile whose record is missing (a log
  // cut short by damage) loses its row and is computed again, with a warning. Tiles the log
  // holds without a row (a crash before their stage was committed, or withdrawn) are
  // forgotten. Errors: the log's, the store's.
  absl::StatusOr<std::vector<int>> ResumeTiles(const std::vector<int>& done_tiles);

  // The engine jobs of the job's lights, and of the refinement levels started so far.
  std::vector<std::string> EngineIds() const;
  // Light `light`'s refinement level, from its start to the job's end (for its tasks and
  // FetchRefinement): its plan fingerprint, and its refined pixels as a blob
  // (core/bake/refined_pixels_codec.h). FAILED_PRECONDITION before it started or once the
  // job ended.
  struct LevelInfo {
    std::string engine_id;
    std::string fingerprint;
    std::shared_ptr<const std::string> refined_pixels;
    int factor = 1;
    int64_t pixels = 0;  // refined
  };
  absl::StatusOr<LevelInfo> Level(int light) const;

  // Light `light`'s progress as its engine job ended (a refined light's base map, while its
  // level runs); nullopt while it runs.
  std::optional<JobProgress> LightEndProgress(int light) const;

  // Light `light`'s tiles (its own indices) that are finished, ascending: those in the log
  // (stored, perhaps not yet committed), those no caster reaches, which are never stored
  // (core/pipeline/unreached_tile.h), and those stored all lit.
  std::vector<int> FinishedTiles(int light) const;

  // Finished tile `tile` of light `light` as a tile file (core/pipeline/tile_file.h), for
  // FetchTile: a tile no caster reaches, or stored all lit, is made from the plan. NOT_FOUND
  // when the tile is not finished (yet); the log's errors.
  absl::StatusOr<std::string> FinishedTileBytes(int light, int tile) const;

  // Writes the job's end state to the store now, without waiting for the end of every light: a
  // cancel's answer then already says CANCELLED. The end writes it again (the same values).
  // False (and logged) when the store refused it.
  bool RecordEnd(JobEnd end, const absl::Status& status);

 private:
  class Light;        // the JobOutput of one light
  class LevelOutput;  // the JobOutput of one light's refinement level
  struct LightLevel;  // a light's refinement level (stored_job_levels.cc)
  // The light's base tiles are all stored: starts its level (BeginLevel) when it has one and
  // pixels to refine, else LightFinished.
  absl::Status BaseFinished(const JobLight& light);
  absl::Status BeginLevel(const JobLight& light);
  // Base tile `tile` of `light` as stored, decoded (made from the plan when it was not stored).
  absl::StatusOr<PdsmTile> BaseTile(const JobLight& light, int tile) const;
  // The level's tiles are all stored: splices them into the base tiles, then LightFinished.
  absl::Status LevelFinished(const JobLight& light);
  std::shared_ptr<LightLevel> LevelOf(int light) const;
  // What `level` holds in memory as it starts (RefinementHooks::hold).
  static int64_t LevelHeldBytes(const LightLevel& level);
  // Base tile `tile` of the level's light as spliced; nullopt when it has no refined pixel.
  static std::optional<EncodedTile> SplicedTile(LightLevel& level, int tile);
  // One of the light's engine jobs (its base's, or its level's) ended: the light ends with
  // the last (LightEnded), as the first of them that did not succeed.
  void EngineJobEnded(const JobLight& light, JobEnd end, const absl::Status& status,
                      const JobProgress& progress, bool level);
  void Started();
  // A tile that the plan alone makes again (MakeUnreachedTile: all lit, the same samples) is
  // stored as a flag of its row in the job store, not as a file: in a sparse world most tiles
  // a caster's box may reach are all lit, and a file each (three syncs) made the coordinator
  // the bottleneck (a 32768^2 sparse world: 413 s through the service, 36 s locally).
  absl::Status StoreTile(const JobLight& light, const PdsmTile& tile);
  // Syncs the log and marks the tiles stored since the last call done, in two transactions
  // (files, all lit). Serialized with WithdrawTiles (commit_mu_), so that a withdrawn tile is
  // never marked done by a commit that had already taken it.
  absl::Status CommitTiles();
  void AddPending(int index, bool all_lit);
  // The log, opened at the first use (ResumeTiles, or the first tile stored).
  absl::StatusOr<TileLog*> Log() const;
  // Appends the tile files of an earlier build (paths_.tiles) to `log`, syncs it and removes
  // them; ResumeTiles then forgets those without a row.
  absl::Status TakeInTileFiles(TileLog* log) const ABSL_EXCLUSIVE_LOCKS_REQUIRED(log_mu_);
  // The light whose tiles hold job tile `index` (the last for an index past them all).
  const JobLight& LightOfTile(int index) const;
  static bool IsMadeFromThePlan(const BakePlan& plan, int tile_index, const PdsmTile& tile);
  // Whether tile `tile` of `light` is not stored but made again from the plan: no caster reaches
  // it, or it was stored all lit. The store's errors (its all-lit tiles, read at the first use).
  absl::StatusOr<bool> IsUnstoredTile(const JobLight& light, int tile) const;
  // The job's tiles (job indices) stored all lit, read from the store at the first use.
  absl::StatusOr<std::vector<bool>> AllLitTiles() const;
  absl::StatusOr<const std::vector<bool>*> AllLitLocked() const
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(all_lit_mu_);
  absl::Status SetAllLit(int index, bool all_lit);
  // Marks the light's tiles no caster reaches done, in one transaction, without files.
  absl::Status StoreUnreachedTiles(const JobLight& light, const std::vector<int>& tiles);
  // Verification found the tiles (the light's own indices) fed by a quarantined worker: their
  // rows leave the store and their files go, until they are stored again.
  absl::Status WithdrawTiles(const JobLight& light, const std::vector<int>& tiles);
  // The light's every tile is stored; the last light to get here writes the file.
  absl::Status LightFinished();
  absl::Status WriteFile();
  void LightEnded(const JobLight& light, JobEnd end, const absl::Status& status,
                  const JobProgress& progress);
  // Once, when the last light has ended.
  void Ended(JobEnd end, const absl::Status& status, int tiles_total);

  JobStore* const store_;
  const JobRecord record_;
  const pdsm::v1::Scene scene_;
  const std::vector<JobLight> lights_;
  const JobPaths paths_;
  const std::function<void(const std::string&)> on_ended_;
  const std::function<void(const absl::Status&)> end_lights_;
  FileSystem* const fs_;
  const RefinementHooks refinement_;
  std::atomic<bool> started_{false};
  std::atomic<bool> ended_{false};  // set by RecordEnd: tiles finishing later are not recorded

  mutable absl::Mutex log_mu_;
  mutable std::unique_ptr<TileLog> log_ ABSL_GUARDED_BY(log_mu_);

  // Held through a commit and a withdrawal; taken before pending_mu_.
  absl::Mutex commit_mu_;
  absl::Mutex pending_mu_;
  // Tiles stored since the last commit: index -> stored all lit. The last store decides.
  std::map<int, bool> pending_ ABSL_GUARDED_BY(pending_mu_);

  mutable absl::Mutex all_lit_mu_;
  mutable std::optional<std::vector<bool>> all_lit_ ABSL_GUARDED_BY(all_lit_mu_);

  mutable absl::Mutex levels_mu_;
  std::vector<std::shared_ptr<LightLevel>> levels_ ABSL_GUARDED_BY(levels_mu_);  // by light

  mutable absl::Mutex mu_;
  std::vector<std::optional<JobProgress>> light_ends_ ABSL_GUARDED_BY(mu_);  // by light
  // By light: its engine jobs still to end, its base's progress as it ended, and the first of
  // their ends that was not kSucceeded.
  struct EngineEnds {
    int pending = 1;
    std::optional<JobProgress> base_progress;
    std::optional<std::pair<JobEnd, absl::Status>> failure;
  };
  std::vector<EngineEnds> engine_ends_ ABSL_GUARDED_BY(mu_);
  int lights_finished_ ABSL_GUARDED_BY(mu_) = 0;
  int lights_ended_ ABSL_GUARDED_BY(mu_) = 0;
  int tiles_total_ ABSL_GUARDED_BY(mu_) = 0;  // of the lights ended so far
  // The first light's end that was not kSucceeded.
  std::optional<std::pair<JobEnd, absl::Status>> first_failure_ ABSL_GUARDED_BY(mu_);
};

}  // namespace pdsm

#endif  // PDSM_SERVER_STORED_JOB_H_
