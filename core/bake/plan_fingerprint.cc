#include "core/bake/plan_fingerprint.h"

#include <cstring>
#include <string_view>
#include <type_traits>

#include "core/assets/mesh_asset.h"
#include "core/bake/refined_pixels.h"

namespace pdsm {
namespace {

// Feeds values by their bytes: bit-exact, so any rounding difference changes the hash.
class Feeder {
 public:
  template <typename T>
  void Add(const T& value) {
    static_assert(std::is_arithmetic_v<T> || std::is_enum_v<T>);
    hash_.Update(std::string_view(reinterpret_cast<const char*>(&value), sizeof(value)));
  }
  void Add(const glm::dvec3& v) { Add(v.x), Add(v.y), Add(v.z); }
  void Add(const glm::vec3& v) { Add(v.x), Add(v.y), Add(v.z); }
  void Add(const std::string& s) {
    Add(s.size());
    hash_.Update(s);
  }
  std::string FinalHex() { return hash_.FinalHex(); }

 private:
  Sha256 hash_;
};

void AddHeader(const PdsmHeader& h, Feeder* f) {
  f->Add(h.format_version), f->Add(h.scene_name), f->Add(h.light_shape);
  f->Add(h.light_half_width), f->Add(h.light_half_height), f->Add(h.light_radius);
  f->Add(h.tan_half_angle);
  const PdsmGeometry& g = h.geometry;
  f->Add(g.projection), f->Add(g.frame.center), f->Add(g.frame.u), f->Add(g.frame.v);
  f->Add(g.frame.n), f->Add(g.width), f->Add(g.height), f->Add(g.s_min), f->Add(g.s_max);
  f->Add(g.t_min), f->Add(g.t_max), f->Add(g.z_near), f->Add(g.z_far);
  f->Add(h.samples), f->Add(h.shadow_map_resolution), f->Add(h.epsilon);
  f->Add(h.compression_metric), f->Add(h.depth_bias), f->Add(h.slope_bias), f->Add(h.sampling);
  f->Add(h.seed), f->Add(h.tile_size);
  f->Add(h.adaptive_tolerance), f->Add(h.adaptive_min_samples);
  f->Add(g.z_valid_min), f->Add(h.surfaces_only), f->Add(h.format_version);
  // Fed only when weighted or refined, so that other plans keep the fingerprints they had.
  if (h.weighting != LightWeighting::kUnweighted) f->Add(h.weighting);
  if (h.max_refinement > 1) f->Add(h.max_refinement);
}

}  // namespace

std::string PlanFingerprint(const BakePlan& plan) {
  Feeder f;
  f.Add(kPlanFingerprintSchema);
  AddHeader(plan.header, &f);
  for (const glm::dvec2& s : plan.samples) f.Add(s.x), f.Add(s.y);
  f.Add(plan.lattice.s_origin), f.Add(plan.lattice.t_origin);
  f.Add(plan.lattice.pitch_s), f.Add(plan.lattice.pitch_t);
  f.Add(plan.z_clip_near), f.Add(plan.z_clip_far);
  f.Add(plan.tiles_x), f.Add(plan.tiles_y);
  f.Add(plan.group_count());  // tasks are per group: the cut must agree too
  for (int i = 0; i < plan.group_count(); ++i) {
    const TileGroup g = plan.group(i);
    f.Add(g.x0), f.Add(g.y0), f.Add(g.width), f.Add(g.height);
  }
  for (const glm::vec3& p : plan.casters.positions) f.Add(p);
  for (uint32_t i : plan.casters.indices) f.Add(i);
  if (!plan.masks.empty()) {  // alpha-tested casters; nothing is added for an opaque scene
    for (const glm::vec2& uv : plan.casters.uvs) f.Add(uv.x), f.Add(uv.y);
    for (uint16_t k : plan.casters.triangle_masks) f.Add(k);
    for (const auto& mask : plan.masks) {
      f.Add(mask->width), f.Add(mask->height), f.Add(static_cast<int>(mask->wrap_u));
      f.Add(static_cast<int>(mask->wrap_v)), f.Add(mask->cutoff);
      f.Add(std::string(mask->alpha.begin(), mask->alpha.end()));
    }
  }
  f.Add(plan.z_scan_floor);
  // The receivers place a surfaces-only plan's depth windows, a refined one's bands and a
  // refinement level's windows.
  if (plan.header.surfaces_only || plan.header.max_refinement > 1 || plan.refined != nullptr) {
    for (const glm::vec3& p : plan.receivers.positions) f.Add(p);
    for (uint32_t i : plan.receivers.indices) f.Add(i);
  }
  // Which of them choose a refined plan's pixels (only when not all: fingerprints of plans
  // without `refine: false` are unchanged).
  if (plan.some_receivers_unrefined) {
    f.Add(std::string("refinable receivers"));
    for (const glm::vec3& p : plan.refinable_receivers.positions) f.Add(p);
    for (uint32_t i : plan.refinable_receivers.indices) f.Add(i);
  }
  if (plan.refined != nullptr) {  // a refinement level: its rays and their bands
    f.Add(plan.refinement);
    for (int t = 0; t < plan.refined->tiles(); ++t) {
      for (const RefinedPixel& p : plan.refined->Tile(t)) {
        f.Add(p.x), f.Add(p.y), f.Add(p.bands.size());
        for (const DepthWindow& band : p.bands) f.Add(band.lo), f.Add(band.hi);
      }
    }
  }
  return f.FinalHex();
}

}  // namespace pdsm
