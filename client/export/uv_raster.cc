#include "client/export/uv_raster.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace pdsm {
namespace {

double Cross(const glm::dvec2& a, const glm::dvec2& b) { return a.x * b.y - a.y * b.x; }

// The point of segment [a, b] nearest q, as the parameter t in [0, 1] along it.
double NearestOnSegment(const glm::dvec2& a, const glm::dvec2& b, const glm::dvec2& q) {
  const glm::dvec2 d = b - a;
  const double length2 = glm::dot(d, d);
  if (length2 == 0.0) return 0.0;
  return std::clamp(glm::dot(q - a, d) / length2, 0.0, 1.0);
}

struct UvTriangle {
  glm::dvec2 t[3];      // texel coordinates
  glm::dvec3 world[3];  // the vertices' world points
  double area2 = 0;     // signed, twice the area in texel units

  // Edge function of edge k (from t[k] to t[k + 1]): > 0 inside, for either winding.
  double Edge(int k, const glm::dvec2& p) const {
    const glm::dvec2& a = t[k];
    const glm::dvec2& b = t[(k + 1) % 3];
    const double e = Cross(b - a, p - a);
    return area2 > 0 ? e : -e;
  }

  // Whether the open texel square [x, x + 1] x [y, y + 1] and the triangle share area: some
  // corner is strictly inside every edge's half-plane (the square's own axes are the caller's
  // bounding-box test).
  bool Overlaps(int x, int y) const {
    for (int k = 0; k < 3; ++k) {
      double most = -std::numeric_limits<double>::infinity();
      for (int c = 0; c < 4; ++c)
        most = std::max(most, Edge(k, glm::dvec2(x + (c & 1), y + (c >> 1))));
      if (most <= 0) return false;
    }
    return true;
  }
};

}  // namespace

ChartRaster RasterizeCharts(std::span<const glm::dvec3> points_world,
                            std::span<const uint32_t> indices, std::span<const glm::vec2> uvs,
                            int width, int height) {
  ChartRaster raster;
  raster.width = width;
  raster.height = height;
  const size_t texels = static_cast<size_t>(width) * height;
  raster.coverage.assign(texels, TexelCoverage::kNone);
  raster.points.assign(texels, glm::dvec3(0.0));
  // Distance from the centre to the point chosen, for kOverlap texels.
  std::vector<double> distance(texels, std::numeric_limits<double>::infinity());
  for (size_t first = 0; first + 2 < indices.size(); first += 3) {
    UvTriangle tri;
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = indices[first + k];
      tri.t[k] =
          glm::dvec2(static_cast<double>(uvs[v].x) * width, static_cast<double>(uvs[v].y) * height);
      tri.world[k] = points_world[v];
    }
    tri.area2 = Cross(tri.t[1] - tri.t[0], tri.t[2] - tri.t[0]);
    if (tri.area2 == 0.0 || !std::isfinite(tri.area2)) continue;
    const glm::dvec2 lo = glm::min(tri.t[0], glm::min(tri.t[1], tri.t[2]));
    const glm::dvec2 hi = glm::max(tri.t[0], glm::max(tri.t[1], tri.t[2]));
    // Texels whose open square meets the box: x < hi.x and x + 1 > lo.x.
    const int x0 = static_cast<int>(std::max(0.0, std::floor(lo.x)));
    const int y0 = static_cast<int>(std::max(0.0, std::floor(lo.y)));
    const int x1 = static_cast<int>(std::min<double>(width - 1, std::ceil(hi.x) - 1));
    const int y1 = static_cast<int>(std::min<double>(height - 1, std::ceil(hi.y) - 1));
    const double abs_area2 = std::abs(tri.area2);
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        const size_t i = raster.Index(x, y);
        if (raster.coverage[i] == TexelCoverage::kCentre) continue;
        const glm::dvec2 q(x + 0.5, y + 0.5);
        const double w0 = tri.Edge(1, q), w1 = tri.Edge(2, q), w2 = tri.Edge(0, q);
        if (w0 >= 0 && w1 >= 0 && w2 >= 0) {
          raster.coverage[i] = TexelCoverage::kCentre;
          raster.points[i] =
              (w0 * tri.world[0] + w1 * tri.world[1] + w2 * tri.world[2]) / abs_area2;
          continue;
        }
        if (!tri.Overlaps(x, y)) continue;
        // The centre is outside: its nearest point is on an edge (the first nearest edge).
        double best = std::numeric_limits<double>::infinity();
        glm::dvec3 point(0.0);
        for (int k = 0; k < 3; ++k) {
          const int j = (k + 1) % 3;
          const double s = NearestOnSegment(tri.t[k], tri.t[j], q);
          const glm::dvec2 p = tri.t[k] + s * (tri.t[j] - tri.t[k]);
          const double d = glm::dot(p - q, p - q);
          if (d < best) {
            best = d;
            point = (1 - s) * tri.world[k] + s * tri.world[j];
          }
        }
        if (best < distance[i]) {
          distance[i] = best;
          raster.coverage[i] = TexelCoverage::kOverlap;
          raster.points[i] = point;
        }
      }
    }
  }
  return raster;
}

int TextureSideFor(std::span<const glm::dvec3> points_world, std::span<const uint32_t> indices,
                   std::span<const glm::vec2> uvs, double texels_per_unit) {
  double world_area = 0, uv_area = 0;
  for (size_t first = 0; first + 2 < indices.size(); first += 3) {
    const uint32_t a = indices[first], b = indices[first + 1], c = indices[first + 2];
    world_area += 0.5 * glm::length(glm::cross(points_world[b] - points_world[a],
                                               points_world[c] - points_world[a]));
    const glm::dvec2 ua(uvs[a]), ub(uvs[b]), uc(uvs[c]);
    uv_area += 0.5 * std::abs(Cross(ub - ua, uc - ua));
  }
  if (!(world_area > 0) || !(uv_area > 0)) return 0;
  const double side = std::ceil(texels_per_unit * std::sqrt(world_area / uv_area));
  if (!std::isfinite(side) || side > std::numeric_limits<int>::max()) {
    return std::numeric_limits<int>::max();
  }
  return std::max(1, static_cast<int>(side));
}

void DilateCharts(int width, int height, int channels, int passes, std::vector<float>* values,
                  std::vector<uint8_t>* covered) {
  std::vector<size_t> grown;
  std::vector<float> sum(channels);
  for (int pass = 0; pass < passes; ++pass) {
    grown.clear();
    std::vector<float> next = *values;
    for (int y = 0; y < height; ++y) {
      for (int x = 0; x < width; ++x) {
        const size_t i = static_cast<size_t>(y) * width + x;
        if ((*covered)[i]) continue;
        std::fill(sum.begin(), sum.end(), 0.0f);
        int n = 0;
        for (int dy = -1; dy <= 1; ++dy) {
          for (int dx = -1; dx <= 1; ++dx) {
            const int nx = x + dx, ny = y + dy;
            if ((dx == 0 && dy == 0) || nx < 0 || ny < 0 || nx >= width || ny >= height) continue;
            const size_t j = static_cast<size_t>(ny) * width + nx;
            if (!(*covered)[j]) continue;
            for (int c = 0; c < channels; ++c) sum[c] += (*values)[j * channels + c];
            ++n;
          }
        }
        if (n == 0) continue;
        for (int c = 0; c < channels; ++c) next[i * channels + c] = sum[c] / n;
        grown.push_back(i);
      }
    }
    if (grown.empty()) return;
    *values = std::move(next);
    for (size_t i : grown) (*covered)[i] = 1;
  }
}

}  // namespace pdsm
