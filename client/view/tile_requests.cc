#include "client/view/tile_requests.h"

#include <algorithm>
#include <cmath>
#include <map>

namespace pdsm::view {

std::vector<TileRequest> TilesSeen(const PdsmHeader& header, std::span<const float> positions_light,
                                   int part, const glm::dmat4* light_from_view) {
  const PdsmGeometry& g = header.geometry;
  const int size = header.tile_size;
  const int tiles_x = (g.width + size - 1) / size;
  const double inv_pitch_s = 1.0 / g.PixelPitchS(), inv_pitch_t = 1.0 / g.PixelPitchT();
  std::map<int64_t, int64_t> pixels;  // tile index -> screen pixels
  // Consecutive screen pixels mostly read the same tiles: count runs before the map.
  int64_t run_key = -1, run_count = 0;
  const auto add = [&](int64_t key) {
    if (key == run_key) {
      ++run_count;
      return;
    }
    if (run_key >= 0) pixels[run_key] += run_count;
    run_key = key;
    run_count = 1;
  };
  for (size_t i = 0; i + 3 < positions_light.size(); i += 4) {
    if (positions_light[i + 3] == 0.0f) continue;  // background
    glm::dvec3 p(positions_light[i], positions_light[i + 1], positions_light[i + 2]);
    if (light_from_view) p = glm::dvec3(*light_from_view * glm::dvec4(p, 1.0));
    const std::optional<glm::dvec2> st = g.WindowFromLight(p);
    if (!st || !(p.z >= g.z_valid_min)) continue;
    const double px = (st->x - g.s_min) * inv_pitch_s, py = (st->y - g.t_min) * inv_pitch_t;
    // shade.frag: outside [0, size] is outside the frustum (NaN too).
    if (!(px >= 0 && px <= g.width && py >= 0 && py <= g.height)) continue;
    const int x_lo = std::clamp(static_cast<int>(std::floor(px - 1.5)), 0, g.width - 1);
    const int x_hi = std::clamp(static_cast<int>(std::floor(px + 0.5)), 0, g.width - 1);
    const int y_lo = std::clamp(static_cast<int>(std::floor(py - 1.5)), 0, g.height - 1);
    const int y_hi = std::clamp(static_cast<int>(std::floor(py + 0.5)), 0, g.height - 1);
    for (int ty = y_lo / size; ty <= y_hi / size; ++ty) {
      for (int tx = x_lo / size; tx <= x_hi / size; ++tx) add(int64_t{ty} * tiles_x + tx);
    }
  }
  if (run_key >= 0) pixels[run_key] += run_count;
  std::vector<TileRequest> requests;
  requests.reserve(pixels.size());
  for (const auto& [key, count] : pixels) {
    requests.push_back(
        {part, static_cast<int>(key % tiles_x), static_cast<int>(key / tiles_x), count});
  }
  return requests;
}

}  // namespace pdsm::view
