#include "worker/group_cache.h"

#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "core/scene/scene_loader.h"
#include "tests/test_support.h"

namespace pdsm {
namespace {

BakePlan PlatesPlan() {
  pdsm::v1::BakeParams overrides;
  overrides.add_resolution(64);
  overrides.add_resolution(64);
  overrides.set_samples(4);
  overrides.set_tile_size(16);
  absl::StatusOr<Scene> scene = LoadSceneFile(testing::ExamplePath("plates"), overrides);
  EXPECT_TRUE(scene.ok()) << scene.status();
  absl::StatusOr<BakePlan> plan = PlanBake(*scene);
  EXPECT_TRUE(plan.ok()) << plan.status();
  return *std::move(plan);
}

TEST(GroupCache, ThreadsAskingForOneGroupShareOnePreparation) {
  const BakePlan plan = PlatesPlan();
  ASSERT_EQ(plan.group_count(), 1u);  // 4x4 tiles, one group
  GroupCache cache(plan);
  std::vector<std::shared_ptr<const PreparedGroup>> got(8);
  std::vector<std::thread> threads;
  for (size_t i = 0; i < got.size(); ++i) {
    threads.emplace_back([&, i] { got[i] = cache.Get(0, plan.group(0).tiles); });
  }
  for (std::thread& t : threads) t.join();
  for (const auto& g : got) EXPECT_EQ(g.get(), got[0].get());
  EXPECT_EQ(got[0]->tiles, plan.group(0).tiles);
  EXPECT_EQ(got[0]->prepared.size(), plan.group(0).tiles.size());
  EXPECT_FALSE(got[0]->empty());
}

TEST(GroupCache, KeepsTheLastUsedAndPreparesTheOthersAgain) {
  const BakePlan plan = PlatesPlan();
  GroupCache cache(plan, /*capacity=*/2);
  const std::vector<int> a = {0, 1}, b = {2, 3}, c = {4, 5};
  const auto first_a = cache.Get(0, a);
  const auto first_b = cache.Get(0, b);
  EXPECT_EQ(cache.Get(0, a).get(), first_a.get());  // a is now the most recent
  cache.Get(0, c);                                  // evicts b
  EXPECT_EQ(cache.Get(0, a).get(), first_a.get());
  EXPECT_NE(cache.Get(0, b).get(), first_b.get());
  EXPECT_EQ(cache.Get(0, b)->tiles, b);
}

}  // namespace
}  // namespace pdsm
