#include "core/util/work_queue.h"

#include <atomic>
#include <chrono>
#include <set>
#include <thread>

#include <gtest/gtest.h>

#include "absl/synchronization/notification.h"

namespace pdsm {
namespace {

TEST(WorkQueue, RunsEveryItemOnItsThreads) {
  WorkQueue queue(3);
  EXPECT_EQ(queue.thread_count(), 3);
  std::atomic<int> sum{0};
  absl::Mutex mu;
  std::set<std::thread::id> threads;
  for (int i = 1; i <= 100; ++i) {
    queue.Post([&, i] {
      sum += i;
      absl::MutexLock lock(&mu);
      threads.insert(std::this_thread::get_id());
    });
  }
  queue.Wait();
  EXPECT_EQ(sum, 5050);
  absl::MutexLock lock(&mu);
  EXPECT_FALSE(threads.contains(std::this_thread::get_id()));
  EXPECT_LE(threads.size(), 3u);
}

TEST(WorkQueue, WaitIncludesWorkPostedByWork) {
  WorkQueue queue(2);
  std::atomic<int> done{0};
  queue.Post([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    queue.Post([&] { ++done; });
    ++done;
  });
  queue.Wait();
  EXPECT_EQ(done, 2);
}

TEST(WorkQueue, StopDropsQueuedWorkAndLetsRunningWorkFinish) {
  WorkQueue queue(1);
  absl::Notification started, release;
  std::atomic<bool> first_finished{false}, second_ran{false};
  queue.Post([&] {
    started.Notify();
    release.WaitForNotification();
    first_finished = true;
  });
  queue.Post([&] { second_ran = true; });
  started.WaitForNotification();
  std::thread stopper([&] { queue.Stop(); });
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  release.Notify();
  stopper.join();
  EXPECT_TRUE(first_finished);
  EXPECT_FALSE(second_ran);
  queue.Post([&] { second_ran = true; });  // ignored after Stop
  queue.Stop();
  EXPECT_FALSE(second_ran);
}

TEST(WorkQueue, AtLeastOneThread) {
  WorkQueue queue(0);
  EXPECT_EQ(queue.thread_count(), 1);
  std::atomic<bool> ran{false};
  queue.Post([&] { ran = true; });
  queue.Wait();
  EXPECT_TRUE(ran);
}

TEST(RunOnAllCores, EveryLoopRunsOnceAndCapsAtMaxThreads) {
  std::atomic<int> loops{0};
  RunOnAllCores(1, [&] { ++loops; });
  EXPECT_EQ(loops, 1);
  loops = 0;
  RunOnAllCores(1000, [&] { ++loops; });
  EXPECT_EQ(loops, CoreCount());
}

}  // namespace
}  // namespace pdsm
