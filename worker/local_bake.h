// The local single-node bake: the service in one process. The same planner, scheduler, stage
// rule and tile assembly as the distributed bake (core/pipeline/bake_engine.h), driven by N
// threads of a WorkQueue, each with its own task runner (its own OSMesa context); no gRPC, no
// sockets. Tiles go into the PDSM file as they finish (worker/local_output.h).
#ifndef PDSM_WORKER_LOCAL_BAKE_H_
#define PDSM_WORKER_LOCAL_BAKE_H_

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "core/pipeline/bake_engine.h"
#include "core/pipeline/tile_assembly.h"
#include "core/scene/scene.h"
#include "core/util/file_system.h"
#include "worker/bake_task.h"

namespace pdsm {

struct BakeProgress {
  int64_t tasks_done = 0;
  int64_t tasks_total = 0;  // known so far: adaptive stages add theirs
  double seconds = 0;
};

struct LocalBakeOptions {
  std::string output_path;  // the .exr; written under a temporary name, renamed at the end
  // A .png of the receivers' attenuation seen from the light; "" none. A scene of several
  // lights writes one per light, at LightPreviewPath(preview_path, name).
  std::string preview_path;
  int threads = 0;           // 0: one per core
  int samples_per_task = 0;  // light samples per task; 0: a default that keeps every thread busy
  // Called from worker threads, serialized, after each task.
  std::function<void(const BakeProgress&)> on_progress;
  FileSystem* fs = nullptr;  // where the PDSM and the preview are written; null: the real one
  // Running event lists held in memory before they move to a scratch file in the output's
  // folder (core/pipeline/event_spill.h): the bake's memory stays flat in the samples.
  // Changes no byte of the PDSM.
  int64_t event_memory_budget_bytes = kDefaultEventMemoryBudget;
};

// Adaptive resolution's part of a bake (bake.maxRefinement > 1; docs/algorithms.md section
// 10): the pixels it refined and what their refinement levels cost (not in BakeSummary's
// counts of the base bake, except tasks and seconds).
struct RefinementSummary {
  int lights = 0;      // lights refined (their pixels chosen)
  int factor = 1;      // their refinement (the largest over lights)
  int64_t pixels = 0;  // refined pixels
  int64_t tasks = 0;
  TaskStats tasks_stats;  // the levels' shadow maps and scan conversion (thread-seconds)
  AssemblyStats assembly;
  double select_seconds = 0;  // choosing the pixels (wall)
  double splice_seconds = 0;  // their sub-functions into the base tiles (wall)
  void Add(const RefinementSummary& o);
};

struct BakeSummary {
  double seconds = 0;
  // The light's name and PDSM size (one-light bakes and each entry of `lights`).
  std::string light_name;
  int width = 0, height = 0, samples = 0;
  int tiles = 0;
  int tiles_all_lit = 0;         // tiles with no vertex at all (no caster can reach their rays)
  int groups = 0;                // tile groups (the unit of rendering)
  int64_t casters = 0;           // caster triangles of the scene
  int64_t casters_left_out = 0;  // of them, out of every tile's reach (BakePlan::casters_left_out)
  int64_t tasks = 0;
  int64_t tile_samples_total = 0;  // light samples summed over tiles (adaptive bakes: < max)
  TaskStats tasks_stats;           // summed over threads (thread-seconds)
  AssemblyStats assembly;
  int64_t spilled_bytes = 0;  // event lists moved to the scratch file (then read back once)
  uint64_t file_bytes = 0;
  RefinementSummary refinement;  // of a refined bake; summed over lights
  // A bake of several lights: each light's own summary, in scene order (their counts summed
  // above; no file_bytes). Empty for one light.
  std::vector<BakeSummary> lights;
};

// The light-view preview of light `light_name` of several: "out.light.png" gives
// "out.light.NAME.png". "" for "".
std::string LightPreviewPath(const std::string& preview_path, const std::string& light_name);

// Bakes every light of `scene`: a one-light scene into a single-part PDSM, several lights one
// after another into the parts of one multipart file (PdsmLightsWriter), in scene order.
// Same scene and parameters give the same file bytes whatever `threads` and
// `samples_per_task`, and the same bytes as the coordinator's bake. The first task that fails
// fails the bake with its status; on error nothing is left at output_path.
absl::StatusOr<BakeSummary> RunLocalBake(const Scene& scene, const LocalBakeOptions& options);

}  // namespace pdsm

#endif  // PDSM_WORKER_LOCAL_BAKE_H_
