// A bake task (the unit of rendering and of distribution): the tiles of one tile group
// (core/bake/tile_groups.h) and a batch of light samples. For each sample the worker renders
// one shadow map for the group — the window its rays' segments cross, drawing only the caster
// clusters that window can see — and scan-converts every ray of the group's tiles through it;
// the result is each tile's per-pixel event lists for that batch.
#ifndef PDSM_WORKER_BAKE_TASK_H_
#define PDSM_WORKER_BAKE_TASK_H_

#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "absl/status/statusor.h"
#include "core/bake/bake_plan.h"
#include "core/bake/tile_reach.h"
#include "core/events/event.h"
#include "worker/group_cache.h"
#include "worker/prepared_group.h"
#include "worker/shadow_map_renderer.h"

namespace pdsm {

struct BakeTask {
  int group_index = 0;
  std::vector<int> tiles;  // tiles of that group, ascending (a later stage may leave some out)
  // [sample_begin, sample_end) of plan.samples. Empty: returned all lit at once.
  int sample_begin = 0;
  int sample_end = 0;
};

struct TaskStats {
  double shadow_map_seconds = 0;  // rendering and read-back
  double scan_seconds = 0;        // scan conversion and per-pixel sorting
  int64_t shadow_maps = 0;
  int64_t shadow_map_texels = 0;
  int64_t triangles_submitted = 0;      // summed over the shadow maps rendered
  int64_t events = 0;                   // before merging
  int64_t texels_walked = 0;            // shadow-map texels visited by scan conversion
  int64_t tiles_skipped = 0;            // tiles no caster reaches (no shadow map at all)
  int64_t ray_segments = 0;             // ray pieces scan-converted (rays x samples, x windows)
  int64_t segments_without_caster = 0;  // of those, pieces whose texels hold no caster: not walked
  void Add(const TaskStats& o);
};

// The camera of the bake's shadow maps (projection, lattice, clip depths, biases), without
// its sample and window.
ShadowMapCamera BakeCamera(const BakePlan& plan);

// Runs tasks of a plan. Owns a renderer (an OSMesa context, ~20 ms of shader compilation to
// make): one runner per thread, kept from one plan (light, job) to the next with SetPlan.
// Not thread-safe; it may pass to another thread as its renderer does (LeaveThread).
class TaskRunner {
 public:
  // A runner with no plan yet (Run and ReceiverDepth: FAILED_PRECONDITION until SetPlan).
  static absl::StatusOr<std::unique_ptr<TaskRunner>> Create();
  // Create(), then SetPlan(plan, groups).
  static absl::StatusOr<std::unique_ptr<TaskRunner>> Create(const BakePlan& plan,
                                                            GroupCache* groups = nullptr);

  // Runs `plan`'s tasks from now on, keeping the renderer. `plan` must outlive its use here,
  // and `groups` (the prepared groups shared with the plan's other runners; null: the runner
  // keeps its own) too. A task gives the same events whatever plans the runner ran before.
  void SetPlan(const BakePlan& plan, GroupCache* groups = nullptr);

  // Unbinds the renderer's context from the calling thread (ShadowMapRenderer::LeaveThread),
  // so that another thread may run this runner next.
  void LeaveThread();

  // One TileEvents per task tile, in order. `cancelled` (optional) is polled before each
  // sample's shadow map: when it returns true the task stops with CANCELLED (a cancelled job or
  // a stopping worker frees the thread promptly). INVALID_ARGUMENT for a group or tile not of
  // the plan; RESOURCE_EXHAUSTED for a shadow map past kMaxShadowMapTexels.
  absl::StatusOr<std::vector<TileEvents>> Run(const BakeTask& task, TaskStats* stats,
                                              const std::function<bool()>& cancelled = nullptr);

  // Light-space depth of the nearest receiver seen along each PDSM ray of the tile (the
  // preview's surface), +infinity where none; row-major over the tile. Consecutive calls
  // upload the receivers once.
  absl::StatusOr<std::vector<float>> ReceiverDepth(const TileRect& tile);

 private:
  explicit TaskRunner(std::unique_ptr<ShadowMapRenderer> renderer)
      : renderer_(std::move(renderer)) {}
  // Prepares the task's group (kept for the next batches of it) and uploads its casters.
  absl::Status Prepare(const BakeTask& task);

  const BakePlan* plan_ = nullptr;  // null until SetPlan
  std::unique_ptr<ShadowMapRenderer> renderer_;
  std::unique_ptr<GroupCache> own_groups_;  // when no shared cache was given
  GroupCache* groups_ = nullptr;
  std::shared_ptr<const PreparedGroup> group_;  // the last task's group, its casters uploaded
  bool receivers_uploaded_ = false;  // the renderer holds the receivers (ReceiverDepth) instead
  bool masks_set_ = false;           // the renderer holds plan_'s alpha masks
};

}  // namespace pdsm

#endif  // PDSM_WORKER_BAKE_TASK_H_
