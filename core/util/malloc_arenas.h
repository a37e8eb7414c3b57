// How many malloc arenas a bake process keeps (glibc). By default every thread that allocates
// may get an arena of its own, up to 8 per core, and each arena keeps the memory its thread
// freed for its own later use: a bake's task threads reallocate their event lists batch after
// batch, so the process held the sum of every thread's peak. Measured on the dragon (512²,
// 2 threads, docs/performance.md "Memory"): peak RSS 194 MiB at 64 samples and 235 MiB at 1024
// with glibc's default, 170 and 188 MiB with two arenas, at the same CPU time (one arena costs
// 30 % more CPU in lock waits).
#ifndef PDSM_CORE_UTIL_MALLOC_ARENAS_H_
#define PDSM_CORE_UTIL_MALLOC_ARENAS_H_

namespace pdsm {

// Caps the arenas at `threads` (at least 2: the main thread's and one the task threads share
// when there are two), unless the user set MALLOC_ARENA_MAX. Call once, before the task
// threads start. Returns the cap in effect (0: glibc's own).
int LimitMallocArenas(int threads);

// Gives the free pages of every arena back to the system (glibc's malloc_trim). For a burst of
// large temporary allocations freed again, which the arena would otherwise keep: the
// coordinator's planning of a submit (a world of 10^6 triangles: RSS 167 MiB after planning,
// for 0.6 MiB of plans kept). Costs a walk over the arenas' free lists.
void ReturnFreeHeapToSystem();

}  // namespace pdsm

#endif  // PDSM_CORE_UTIL_MALLOC_ARENAS_H_
