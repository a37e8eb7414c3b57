#include "core/bake/scene_index.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <tuple>

#include "absl/strings/str_format.h"
#include "core/bake/caster_clusters.h"

namespace pdsm {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// The bits of v (< 2^21) spread to every third bit of a 64-bit word.
uint64_t SpreadBits(uint64_t v) {
  v &= 0x1fffff;
  v = (v | v << 32) & 0x1f00000000ffffULL;
  v = (v | v << 16) & 0x1f0000ff0000ffULL;
  v = (v | v << 8) & 0x100f00f00f00f00fULL;
  v = (v | v << 4) & 0x10c30c30c30c30c3ULL;
  v = (v | v << 2) & 0x1249249249249249ULL;
  return v;
}

// The Morton code of a point of the box [lo, hi], 21 bits per axis over cubic cells (its
// longest side cut in 2^21: 0.5 mm over a 1 km world, so a tree crown's small triangles still
// sort among themselves; a flat world's first splits go across its long sides).
class MortonCode {
 public:
  MortonCode(const glm::dvec3& lo, const glm::dvec3& hi) : lo_(lo) {
    const double extent = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
    scale_ = extent > 0 ? kMaxCell / extent : 0;
  }
  uint64_t operator()(const glm::dvec3& p) const {
    uint64_t code = 0;
    for (int i = 0; i < 3; ++i) {
      const double cell = std::clamp(std::floor((p[i] - lo_[i]) * scale_), 0.0, kMaxCell);
      code |= SpreadBits(static_cast<uint64_t>(cell)) << i;
    }
    return code;
  }

 private:
  static constexpr double kMaxCell = (1 << 21) - 1;
  glm::dvec3 lo_;
  double scale_ = 0;
};

// The plan numbers of the casters' masks, as a plan has always numbered them: meshes in order,
// each mask where it is first met, equal masks (the same file twice) one number.
absl::Status NumberMasks(const Scene& scene, std::vector<std::shared_ptr<const AlphaMask>>* masks,
                         std::vector<std::vector<uint16_t>>* numbers) {
  numbers->assign(scene.meshes.size(), {});
  for (size_t m = 0; m < scene.meshes.size(); ++m) {
    const TriangleMesh& mesh = scene.meshes[m];
    if (!Casts(mesh.role) || !mesh.has_masks()) continue;
    std::vector<uint16_t>& number = (*numbers)[m];
    number.assign(mesh.masks.size() + 1, 0);
    for (size_t k = 0; k < mesh.masks.size(); ++k) {
      const size_t index =
          std::find_if(masks->begin(), masks->end(),
                       [&](const auto& mask) {
                         return mask == mesh.masks[k] || SameMask(*mask, *mesh.masks[k]);
                       }) -
          masks->begin();
      if (index == masks->size()) {
        if (index == UINT16_MAX) {
          return absl::InvalidArgumentError(
              absl::StrFormat("%s: more than %d alpha-tested textures in the scene",
                              scene.source_path, UINT16_MAX));
        }
        masks->push_back(mesh.masks[k]);
      }
      number[k + 1] = static_cast<uint16_t>(index + 1);
    }
  }
  return absl::OkStatus();
}

}  // namespace

LightBox LightBoxOf(const LightFrame& frame, const glm::dvec3& world_lo,
                    const glm::dvec3& world_hi) {
  // Each rounded step of LightFromWorld (a difference, products by the frame's fixed axes, their
  // sum) is monotone in its inputs, so each light-space coordinate as computed is monotone in
  // each world coordinate: its least and greatest over the box are at corners, exactly.
  LightBox box{glm::dvec3(kInf), glm::dvec3(-kInf)};
  for (int k = 0; k < 8; ++k) {
    const glm::dvec3 p =
        frame.LightFromWorld({(k & 1) ? world_hi.x : world_lo.x, (k & 2) ? world_hi.y : world_lo.y,
                              (k & 4) ? world_hi.z : world_lo.z});
    box.lo = glm::min(box.lo, p);
    box.hi = glm::max(box.hi, p);
  }
  // A plan's casters are float, and rounding to float is monotone too.
  box.lo = glm::min(box.lo, glm::dvec3(glm::vec3(box.lo)));
  box.hi = glm::max(box.hi, glm::dvec3(glm::vec3(box.hi)));
  return box;
}

absl::StatusOr<std::shared_ptr<const SceneIndex>> SceneIndex::Build(const Scene& scene) {
  auto index = std::make_shared<SceneIndex>();
  index->scene_ = &scene;
  if (absl::Status s = NumberMasks(scene, &index->masks_, &index->mask_numbers_); !s.ok()) {
    return s;
  }
  glm::dvec3 lo(kInf), hi(-kInf);
  size_t triangle_count = 0;
  for (const TriangleMesh& mesh : scene.meshes) {
    for (const glm::dvec3& p : mesh.positions_world) {
      lo = glm::min(lo, p);
      hi = glm::max(hi, p);
    }
    triangle_count += mesh.indices.size() / 3;
  }
  if (lo.x <= hi.x) index->lo_ = lo, index->hi_ = hi;

  // Sorted by (group, Morton code of the centroid), ties in scene order.
  struct Entry {
    uint32_t group;
    uint64_t code;
    SceneTriangle triangle;
  };
  std::vector<Entry> entries;
  entries.reserve(triangle_count);
  const MortonCode morton(lo, hi);
  for (size_t m = 0; m < scene.meshes.size(); ++m) {
    const TriangleMesh& mesh = scene.meshes[m];
    const std::vector<uint16_t>& numbers = index->mask_numbers_[m];
    for (size_t t = 0; 3 * t + 2 < mesh.indices.size(); ++t) {
      uint32_t group = kReceiverOnlyGroup;
      if (Casts(mesh.role)) group = numbers.empty() ? 0 : numbers[mesh.triangle_masks[t]];
      const glm::dvec3 centroid = (mesh.positions_world[mesh.indices[3 * t]] +
                                   mesh.positions_world[mesh.indices[3 * t + 1]] +
                                   mesh.positions_world[mesh.indices[3 * t + 2]]) /
                                  3.0;
      entries.push_back(Entry{group, morton(centroid),
                              SceneTriangle{static_cast<uint32_t>(m), static_cast<uint32_t>(t)}});
    }
  }
  std::sort(entries.begin(), entries.end(), [](const Entry& a, const Entry& b) {
    return std::tie(a.group, a.code, a.triangle.mesh, a.triangle.triangle) <
           std::tie(b.group, b.code, b.triangle.mesh, b.triangle.triangle);
  });
  index->triangles_.reserve(entries.size());
  for (const Entry& e : entries) {
    index->triangles_.push_back(e.triangle);
    if (e.group < kReceiverOnlyGroup) ++index->caster_count_;
  }

  // Clusters: runs within a group.
  for (size_t first = 0; first < entries.size();) {
    SceneCluster c;
    c.first = static_cast<uint32_t>(first);
    c.group = entries[first].group;
    c.casts = c.group < kReceiverOnlyGroup;
    c.lo = glm::dvec3(kInf);
    c.hi = glm::dvec3(-kInf);
    size_t end = first;
    while (end < entries.size() && end - first < kClusterTriangles &&
           entries[end].group == c.group) {
      const TriangleMesh& mesh = scene.meshes[entries[end].triangle.mesh];
      c.receives = c.receives || Receives(mesh.role);
      for (int v = 0; v < 3; ++v) {
        const glm::dvec3& p =
            mesh.positions_world[mesh.indices[3 * entries[end].triangle.triangle + v]];
        c.lo = glm::min(c.lo, p);
        c.hi = glm::max(c.hi, p);
      }
      ++end;
    }
    c.count = static_cast<uint32_t>(end - first);
    index->clusters_.push_back(c);
    first = end;
  }

  // The tree, level by level, until one box is left.
  std::vector<Box> level;
  level.reserve(index->clusters_.size());
  for (const SceneCluster& c : index->clusters_)
    level.push_back(Box{c.lo, c.hi, c.casts, c.receives});
  while (level.size() > 1 || (index->tree_.empty() && !level.empty())) {
    std::vector<Box> up;
    up.reserve((level.size() + kTreeFanout - 1) / kTreeFanout);
    for (size_t i = 0; i < level.size(); i += kTreeFanout) {
      Box box{glm::dvec3(kInf), glm::dvec3(-kInf)};
      for (size_t j = i; j < std::min(level.size(), i + kTreeFanout); ++j) {
        box.lo = glm::min(box.lo, level[j].lo);
        box.hi = glm::max(box.hi, level[j].hi);
        box.casts = box.casts || level[j].casts;
        box.receives = box.receives || level[j].receives;
      }
      up.push_back(box);
    }
    index->tree_.push_back(up);
    level = std::move(up);
  }
  return std::shared_ptr<const SceneIndex>(std::move(index));
}

}  // namespace pdsm
