#include "worker/bake_task.h"

#include <gtest/gtest.h>

#include <memory>
#include <thread>
#include <vector>

#include "core/bake/bake_plan.h"
#include "core/geometry/light_frame.h"
#include "core/scene/scene.h"

namespace pdsm {
namespace {

TriangleMesh Quad(double half, double y, MeshRole role) {
  TriangleMesh mesh;
  mesh.role = role;
  mesh.positions_world = {{-half, y, -half}, {half, y, -half}, {half, y, half}, {-half, y, half}};
  mesh.indices = {0, 1, 2, 0, 2, 3};
  return mesh;
}

// A plate over a ground under a rect light (`disk`: a disk light, off centre) and its plan.
std::unique_ptr<BakePlan> PlatePlan(bool disk) {
  Scene scene;
  scene.name = "runner";
  scene.meshes = {Quad(3, 0, MeshRole::kReceiverOnly), Quad(1, 2, MeshRole::kCasterAndReceiver)};
  const glm::dvec3 up(0, 0, 1);
  scene.light.shape = disk ? LightShape::kDisk : LightShape::kRect;
  scene.light.frame = MakeLightFrame({disk ? 0.7 : 0.0, 5, 0}, {0, -1, 0}, &up);
  scene.light.half_width = scene.light.half_height = 0.5;
  scene.light.radius = 0.8;
  scene.bake.width = scene.bake.height = 24;
  scene.bake.tile_size = 8;
  scene.bake.samples = 8;
  scene.bake.shadow_map_resolution = disk ? 96 : 64;  // other window sizes than the rect's
  absl::StatusOr<BakePlan> plan = PlanBake(scene);
  EXPECT_TRUE(plan.ok()) << plan.status();
  return plan.ok() ? std::make_unique<BakePlan>(*std::move(plan)) : nullptr;
}

// Every group's events for all samples, in group order.
std::vector<TileEvents> RunAll(TaskRunner* runner, const BakePlan& plan) {
  std::vector<TileEvents> all;
  for (int g = 0; g < plan.group_count(); ++g) {
    TaskStats stats;
    absl::StatusOr<std::vector<TileEvents>> events =
        runner->Run(BakeTask{g, plan.group(g).tiles, 0, plan.header.samples}, &stats);
    EXPECT_TRUE(events.ok()) << events.status();
    if (!events.ok()) return all;
    for (TileEvents& tile : *events) all.push_back(std::move(tile));
  }
  return all;
}

void ExpectSameEvents(const std::vector<TileEvents>& got, const std::vector<TileEvents>& want) {
  ASSERT_EQ(got.size(), want.size());
  for (size_t i = 0; i < got.size(); ++i) {
    EXPECT_EQ(got[i].offsets, want[i].offsets) << "tile " << i;
    EXPECT_TRUE(got[i].events == want[i].events) << "tile " << i;
  }
}

// The local bake and the remote worker keep one runner (its GL context) from light to light,
// and the local bake hands it to another thread for the next light: a task's events must not
// depend on what the runner ran before, nor on which thread runs it.
TEST(TaskRunner, KeptAcrossPlansAndThreadsGivesTheEventsOfAFreshRunner) {
  const std::unique_ptr<BakePlan> rect = PlatePlan(false);
  const std::unique_ptr<BakePlan> disk = PlatePlan(true);
  ASSERT_TRUE(rect && disk);
  std::vector<TileEvents> fresh_rect, fresh_disk;
  {
    absl::StatusOr<std::unique_ptr<TaskRunner>> runner = TaskRunner::Create(*rect);
    ASSERT_TRUE(runner.ok()) << runner.status();
    fresh_rect = RunAll(runner->get(), *rect);
  }
  {
    absl::StatusOr<std::unique_ptr<TaskRunner>> runner = TaskRunner::Create(*disk);
    ASSERT_TRUE(runner.ok()) << runner.status();
    fresh_disk = RunAll(runner->get(), *disk);
  }
  size_t shadowed = 0;
  for (const TileEvents& tile : fresh_rect) shadowed += tile.events.size();
  ASSERT_GT(shadowed, 0u);  // the plate's shadow is in the map

  absl::StatusOr<std::unique_ptr<TaskRunner>> kept = TaskRunner::Create();
  ASSERT_TRUE(kept.ok()) << kept.status();
  TaskStats stats;
  EXPECT_EQ((*kept)->Run(BakeTask{0, {0}, 0, 1}, &stats).status().code(),
            absl::StatusCode::kFailedPrecondition);  // no plan yet
  (*kept)->SetPlan(*rect);
  ASSERT_TRUE((*kept)->ReceiverDepth(rect->tile(0)).ok());  // leaves the receivers uploaded
  ExpectSameEvents(RunAll(kept->get(), *rect), fresh_rect);
  (*kept)->LeaveThread();
  std::thread other([&] {
    (*kept)->SetPlan(*disk);
    ExpectSameEvents(RunAll(kept->get(), *disk), fresh_disk);
    (*kept)->LeaveThread();
  });
  other.join();
  (*kept)->SetPlan(*rect);
  ExpectSameEvents(RunAll(kept->get(), *rect), fresh_rect);
}

}  // namespace
}  // namespace pdsm
