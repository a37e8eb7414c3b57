#include "worker/group_cache.h"

#include <algorithm>

namespace pdsm {

GroupCache::GroupCache(const BakePlan& plan, size_t capacity)
    : plan_(plan), capacity_(std::max<size_t>(1, capacity)) {}

bool GroupCache::Ready(Waiter* waiter) {
  waiter->cache->mu_.AssertHeld();  // absl::Condition calls it with the mutex held
  const auto it = waiter->cache->entries_.find(*waiter->key);
  return it == waiter->cache->entries_.end() || it->second.group != nullptr;
}

std::shared_ptr<const PreparedGroup> GroupCache::Get(int group_index,
                                                     const std::vector<int>& tiles) {
  const Key key(group_index, tiles);
  {
    absl::MutexLock lock(&mu_);
    // Another runner preparing it: wait for it (or for its failure to leave no entry).
    Waiter waiter{this, &key};
    mu_.Await(absl::Condition(&GroupCache::Ready, &waiter));
    if (auto it = entries_.find(key); it != entries_.end()) {
      it->second.last_use = ++uses_;
      return it->second.group;
    }
    entries_[key] = Entry{nullptr, ++uses_};
  }
  auto prepared = std::make_shared<const PreparedGroup>(PrepareGroup(plan_, group_index, tiles));
  absl::MutexLock lock(&mu_);
  entries_[key].group = prepared;
  // Drop the least recently used ready entries beyond the capacity (runners keep theirs).
  while (entries_.size() > capacity_) {
    auto oldest = entries_.end();
    for (auto it = entries_.begin(); it != entries_.end(); ++it) {
      if (it->second.group &&
          (oldest == entries_.end() || it->second.last_use < oldest->second.last_use)) {
        oldest = it;
      }
    }
    if (oldest == entries_.end()) break;
    entries_.erase(oldest);
  }
  return prepared;
}

}  // namespace pdsm
