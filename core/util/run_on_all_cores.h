// Runs one work loop on every core and waits: the calling thread plus up to
// hardware_concurrency - 1 more. The loops share their items through a counter of the caller's,
// and each writes only its own items' results, so results do not depend on the scheduling.
#ifndef PDSM_CORE_UTIL_RUN_ON_ALL_CORES_H_
#define PDSM_CORE_UTIL_RUN_ON_ALL_CORES_H_

#include <algorithm>
#include <cstddef>
#include <thread>
#include <vector>

namespace pdsm {

// `work` runs once per thread; `max_threads` (e.g. the item count) caps the threads, >= 1.
template <typename Work>
void RunOnAllCores(size_t max_threads, const Work& work) {
  const size_t threads = std::clamp<size_t>(std::thread::hardware_concurrency(), 1,
                                            std::max<size_t>(max_threads, 1));
  std::vector<std::thread> pool;
  for (size_t t = 1; t < threads; ++t) pool.emplace_back(work);
  work();
  for (std::thread& thread : pool) thread.join();
}

}  // namespace pdsm

#endif  // PDSM_CORE_UTIL_RUN_ON_ALL_CORES_H_
