// A coordinator's job while it runs, and where its results go (a JobOutput,
// core/pipeline/bake_engine.h). Under DATA_DIR/jobs/<id>/:
//   tiles/<index>.tile  each finished tile (core/pipeline/tile_file.h), durable once its row
//                       is in the job store (MarkTileDone), so a restart resumes the job with
//                       only its missing tiles;
//   pdsm.exr            the PDSM, written from the tile files when every tile is stored.
// The job's states (RUNNING, SUCCEEDED, FAILED, CANCELLED) go to the job store as they come.
//
// Thread-safe: the engine calls the JobOutput methods from its executor, the coordinator the
// accessors from its gRPC threads.
#ifndef PDSM_SERVER_STORED_JOB_H_
#define PDSM_SERVER_STORED_JOB_H_

#include <atomic>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/bake/bake_plan.h"
#include "core/pipeline/bake_engine.h"
#include "core/util/file_system.h"
#include "pdsm/v1/scene.pb.h"
#include "server/job_store.h"

namespace pdsm {

// Where a job's files are.
struct JobPaths {
  JobPaths(const std::string& data_dir, const std::string& job_id);
  std::string dir;    // DATA_DIR/jobs/<id>
  std::string tiles;  // its tiles/
  std::string pdsm;   // its pdsm.exr
  std::string Tile(int tile_index) const;
};

class StoredJob final : public JobOutput {
 public:
  // `store` outlives this. `on_ended(job_id)` runs at the end of Ended(). `fs`: where tile
  // files and the PDSM are written (null: the real file system).
  StoredJob(JobStore* store, const std::string& data_dir, JobRecord record, pdsm::v1::Scene scene,
            std::shared_ptr<const BakePlan> plan, std::function<void(const std::string&)> on_ended,
            FileSystem* fs = nullptr);

  const JobRecord& record() const { return record_; }  // as it was when the job was activated
  const pdsm::v1::Scene& scene() const { return scene_; }
  const std::shared_ptr<const BakePlan>& plan() const { return plan_; }
  const std::string& fingerprint() const { return fingerprint_; }
  const JobPaths& paths() const { return paths_; }
  bool ended() const { return ended_; }

  // The tiles whose files are complete (written under a temporary name, then renamed),
  // ascending.
  std::vector<int> FinishedTiles() const;

  // Writes the job's end state to the store now, without waiting for Ended(): a cancel's
  // answer then already says CANCELLED. Ended() writes it again (the same values). False (and
  // logged) when the store refused it.
  bool RecordEnd(JobEnd end, const absl::Status& status);

  void Started() override;
  absl::Status StoreTile(const PdsmTile& tile) override;
  absl::Status Finish() override;
  void Ended(JobEnd end, const absl::Status& status, const JobProgress& progress) override;

 private:
  JobStore* const store_;
  const JobRecord record_;
  const pdsm::v1::Scene scene_;
  const std::shared_ptr<const BakePlan> plan_;
  const std::string fingerprint_;
  const JobPaths paths_;
  const std::function<void(const std::string&)> on_ended_;
  FileSystem* const fs_;
  std::atomic<bool> ended_{false};  // set by RecordEnd: tiles finishing later are not recorded
};

}  // namespace pdsm

#endif  // PDSM_SERVER_STORED_JOB_H_
