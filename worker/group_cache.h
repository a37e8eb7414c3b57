// Prepared tile groups (worker/prepared_group.h) shared by the task runners of one plan — the
// local bake's threads, a remote worker's threads on one job — so that each group is prepared
// once, by the first runner that needs it, while the others wait for it rather than repeat it.
#ifndef PDSM_WORKER_GROUP_CACHE_H_
#define PDSM_WORKER_GROUP_CACHE_H_

#include <cstddef>
#include <map>
#include <memory>
#include <utility>
#include <vector>

#include "absl/base/thread_annotations.h"
#include "absl/synchronization/mutex.h"
#include "core/bake/bake_plan.h"
#include "worker/prepared_group.h"

namespace pdsm {

// Thread-safe. Keeps the `capacity` groups asked for last (runners work on few groups at a
// time: the scheduler opens groups in order).
class GroupCache {
 public:
  // `plan` outlives the cache.
  explicit GroupCache(const BakePlan& plan, size_t capacity = 8);

  // The prepared group; prepared here on first use. REQUIRES: `tiles` are of the group.
  std::shared_ptr<const PreparedGroup> Get(int group_index, const std::vector<int>& tiles);

 private:
  using Key = std::pair<int, std::vector<int>>;
  struct Entry {
    std::shared_ptr<const PreparedGroup> group;  // null while being prepared
    uint64_t last_use = 0;
  };
  struct Waiter {
    GroupCache* cache;
    const Key* key;
  };
  // Whether `key` may be looked up: prepared, or absent (not being prepared by another).
  static bool Ready(Waiter* waiter);

  const BakePlan& plan_;
  const size_t capacity_;
  mutable absl::Mutex mu_;
  std::map<Key, Entry> entries_ ABSL_GUARDED_BY(mu_);
  uint64_t uses_ ABSL_GUARDED_BY(mu_) = 0;
};

}  // namespace pdsm

#endif  // PDSM_WORKER_GROUP_CACHE_H_
