#include "core/util/malloc_arenas.h"

#include <malloc.h>

#include <algorithm>
#include <cstdlib>

namespace pdsm {

int LimitMallocArenas(int threads) {
  if (std::getenv("MALLOC_ARENA_MAX") != nullptr) return 0;  // glibc read it at start-up
  const int arenas = std::max(2, threads);
  return mallopt(M_ARENA_MAX, arenas) == 1 ? arenas : 0;
}

void ReturnFreeHeapToSystem() { malloc_trim(0); }

}  // namespace pdsm
