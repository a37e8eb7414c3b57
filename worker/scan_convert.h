// Scan conversion of one PDSM ray through one light sample's shadow map (thesis 3.1).
// The ray is a straight segment in the shadow map; walk the texels it crosses in order of
// increasing depth. In a texel the ray spans depths [z_in, z_out] and the texel holds the
// (biased) occluder depth z_sm:
//   z_sm <= z_in          the whole piece is behind the occluder: enter shadow at z_in
//                         (fig. 3.4b) unless already shadowed;
//   z_in < z_sm < z_out   the ray passes behind the occluder at z_sm: enter at z_sm
//                         (fig. 3.4a); if it was shadowed, it is lit from z_in to z_sm, so it
//                         first leaves at z_in;
//   z_sm >= z_out         lit: a shadowed ray leaves at z_in, the boundary with the previous
//                         texel (fig. 3.4c).
// A ray that stays in one texel (the sample at the light centre) is the thesis' special case:
// shadowed from z_sm to infinity.
#ifndef PDSM_WORKER_SCAN_CONVERT_H_
#define PDSM_WORKER_SCAN_CONVERT_H_

#include <cstdint>
#include <vector>

#include "core/bake/shadow_map_lattice.h"
#include "core/bake/tile_reach.h"
#include "core/events/event.h"
#include "core/pdsm/pdsm_geometry.h"

namespace pdsm {

// A rendered shadow map: a window of the global lattice, row-major from the window's lowest
// (s, t), holding biased light-space depths (+infinity where no caster). `occupancy`, when
// given, is BuildOccupancySums' table of the same map: a ray whose texels' box holds no caster
// is then skipped without a walk (most rays of a bake cross no caster at all).
struct ShadowMapView {
  const float* depth = nullptr;
  ShadowMapLattice lattice;
  ShadowMapWindow window;
  const uint32_t* occupancy = nullptr;
};

// The summed-area table of the texels holding a caster (depth < +infinity): (width + 1) x
// (height + 1) counts, row-major, sums[(y + 1) * (width + 1) + x + 1] = the count in
// [0, x] x [0, y]. REQUIRES width * height < 2^32.
void BuildOccupancySums(const float* depth, int width, int height, std::vector<uint32_t>* sums);

// What a segment's end means: kOpen, the ray's state holds on (the ray's natural end);
// kClose, the segment is one piece of the ray (a surfaces-only depth window): a shadowed ray
// leaves at ray.z_far, so the next piece starts lit and counts do not pile up.
enum class SegmentEnd { kOpen, kClose };

// Appends the ray's events for this sample between ray.z_near and ray.z_far, in increasing
// depth, to `events`: counts of +key entering shadow and -key leaving it (key 1 for a counted
// bake, SampleEventKey(k) for a sample-keyed one: core/events/event.h). Starting mid-ray is exact
// from the start on: a texel's state depends only on its own depth (enter at z_near when the first
// texel is already behind a caster). REQUIRES: the ray's segment lies inside the view's window
// (ShadowMapWindowFor). Returns the number of texels walked (0 for a ray the occupancy table skips:
// it has no events, as its walk would have found none).
int64_t ScanConvertRay(const ShadowMapView& shadow_map, const RayInShadowMap& ray,
                       Projection projection, std::vector<Event>* events,
                       SegmentEnd end = SegmentEnd::kOpen, int32_t key = 1);

}  // namespace pdsm

#endif  // PDSM_WORKER_SCAN_CONVERT_H_
