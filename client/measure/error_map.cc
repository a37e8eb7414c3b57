#include "client/measure/error_map.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "client/export/attenuation_image.h"
#include "client/view/image_io.h"
#include "client/view/text_overlay.h"
#include "core/pdsm/refined_pixel.h"

namespace pdsm {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
// How far each receiver point moves toward the light, relative to its depth (MeasureErrorMap).
constexpr double kTowardTheLight = 1e-6;

// The light-space point at depth z on PDSM pixel (x, y)'s ray (core/pdsm/pdsm_geometry.h).
glm::dvec3 PointOnRay(const PdsmGeometry& g, int x, int y, double z) {
  const double s = g.PixelCenterS(x), t = g.PixelCenterT(y);
  return g.projection == Projection::kOrthographic ? glm::dvec3(s, t, z)
                                                   : glm::dvec3(s * z, t * z, z);
}

// The value at rank q of sorted values (nearest rank, as the sweep's percentiles).
double Percentile(const std::vector<double>& sorted, double q) {
  if (sorted.empty()) return 0;
  const size_t rank = static_cast<size_t>(std::ceil(q * static_cast<double>(sorted.size())));
  return sorted[std::clamp<size_t>(rank, 1, sorted.size()) - 1];
}

ErrorStats99 Stats(std::vector<double> errors) {
  ErrorStats99 out;
  out.count = errors.size();
  if (errors.empty()) return out;
  std::sort(errors.begin(), errors.end());
  double sum = 0;
  for (double e : errors) sum += e;
  out.mean = sum / static_cast<double>(errors.size());
  out.p95 = Percentile(errors, 0.95);
  out.p99 = Percentile(errors, 0.99);
  out.max = errors.back();
  return out;
}

}  // namespace

absl::StatusOr<ErrorMap> MeasureErrorMap(const PdsmImage& pdsm, const Scene& scene,
                                         const ReferenceOptions& reference, int step) {
  if (step < 1)
    return absl::InvalidArgumentError(absl::StrCat("step: must be >= 1 (got ", step, ")"));
  absl::StatusOr<AttenuationImage> surface = AttenuationOnReceivers(pdsm, scene);
  if (!surface.ok()) return surface.status();
  const PdsmGeometry& g = pdsm.header.geometry;
  ErrorMap map;
  map.step = step;
  map.width = (surface->width + step - 1) / step;
  map.height = (surface->height + step - 1) / step;
  map.method = ResolveReferenceMethod(reference.method, scene);
  map.reference_samples = map.method == ReferenceMethod::kEmbree ? reference.samples : 0;
  const size_t pixels = static_cast<size_t>(map.width) * map.height;
  map.pdsm.assign(pixels, kNaN);
  map.reference.assign(pixels, kNaN);
  map.point.assign(pixels, glm::dvec3(std::numeric_limits<double>::quiet_NaN()));
  // The defined pixels' world points, for one call of the reference (it parallelises inside).
  std::vector<size_t> where;
  std::vector<glm::dvec3> points;
  for (int r = 0; r < map.height; ++r) {
    for (int c = 0; c < map.width; ++c) {
      const int column = c * step, row = r * step;
      const size_t source = static_cast<size_t>(row) * surface->width + column;
      if (std::isnan(surface->attenuation[source])) continue;
      const size_t pixel = static_cast<size_t>(r) * map.width + c;
      // Image pixel (column, row) is PDSM pixel (width - 1 - column, height - 1 - row).
      const int x = g.width - 1 - column, y = g.height - 1 - row;
      // Nudged toward the light: on a tilted receiver, a point on its plane within rounding
      // is hidden by its own triangle half the time, in the exact reference, when it lands
      // behind the plane (the plane then fills the sky above it). A millionth of the depth
      // is far above rounding and far below any feature or the bake's depth bias.
      const double z = static_cast<double>(surface->depth[source]);
      const double nudged = z - kTowardTheLight * std::max(std::abs(z), g.z_far - g.z_near);
      if (nudged < g.z_valid_min) continue;
      map.pdsm[pixel] = EvaluatePixelCentre(pdsm.Function(x, y), nudged);
      const glm::dvec3 light = PointOnRay(g, x, y, nudged);
      where.push_back(pixel);
      points.push_back(g.frame.WorldFromLight(light));
      map.point[pixel] = points.back();
    }
  }
  absl::StatusOr<std::vector<double>> truth = ReferenceAttenuation(scene, points, reference);
  if (!truth.ok()) return truth.status();
  for (size_t k = 0; k < where.size(); ++k) {
    const double value = (*truth)[k];
    if (std::isnan(value)) {
      map.pdsm[where[k]] = kNaN;  // behind the light: neither says anything
      map.point[where[k]] = glm::dvec3(std::numeric_limits<double>::quiet_NaN());
    } else {
      map.reference[where[k]] = static_cast<float>(value);
    }
  }
  return map;
}

ErrorMapSummary SummarizeErrorMap(const ErrorMap& map) {
  std::vector<double> all, penumbra;
  for (size_t p = 0; p < map.pdsm.size(); ++p) {
    if (std::isnan(map.pdsm[p]) || std::isnan(map.reference[p])) continue;
    const double error = map.Error(p);
    all.push_back(error);
    if (map.reference[p] > 0.0f && map.reference[p] < 1.0f) penumbra.push_back(error);
  }
  return ErrorMapSummary{Stats(std::move(all)), Stats(std::move(penumbra))};
}

void ErrorColour(double error, double max_error, unsigned char rgb[3]) {
  // matplotlib's viridis at 0, 1/8, ..., 1, interpolated linearly in between.
  static constexpr unsigned char kViridis[9][3] = {{68, 1, 84},    {71, 44, 122},  {59, 81, 139},
                                                   {44, 113, 142}, {33, 144, 141}, {39, 173, 129},
                                                   {92, 200, 99},  {170, 220, 50}, {253, 231, 37}};
  if (std::isnan(error)) {
    rgb[0] = rgb[1] = rgb[2] = kNoValueGrey;
    return;
  }
  const double u = std::clamp(error / max_error, 0.0, 1.0) * 8.0;
  const int i = std::min(static_cast<int>(u), 7);
  const double f = u - i;
  for (int c = 0; c < 3; ++c) {
    rgb[c] = static_cast<unsigned char>(
        std::lround((1.0 - f) * kViridis[i][c] + f * kViridis[i + 1][c]));
  }
}

std::string ErrorMapTitle(const ErrorMap& map) {
  const std::string reference = map.method == ReferenceMethod::kEmbree
                                    ? absl::StrFormat("embree %d samples", map.reference_samples)
                                    : std::string(ReferenceMethodName(map.method));
  const std::string pixels =
      map.step == 1 ? "every pixel" : absl::StrFormat("1 of %dx%d pixels", map.step, map.step);
  return absl::StrFormat("|pdsm - %s| on the receivers, %s", reference, pixels);
}

std::string FormatErrorStats(const ErrorStats99& s) {
  return absl::StrFormat("mean %.4f  p95 %.4f  p99 %.4f  max %.4f (%d px)", s.mean, s.p95, s.p99,
                         s.max, s.count);
}

absl::Status WriteErrorMapPng(const ErrorMap& map, const ErrorMapSummary& summary, double max_error,
                              const std::string& title, const std::string& path, FileSystem* fs) {
  if (!(std::isfinite(max_error) && max_error > 0)) {
    return absl::InvalidArgumentError(
        absl::StrCat("max error: must be a positive number (got ", max_error, ")"));
  }
  const int zoom = std::max(1, 512 / std::max({map.width, map.height, 1}));
  const int text = 1, margin = 8;
  const std::vector<std::string> lines = {
      title, absl::StrCat("all       ", FormatErrorStats(summary.all)),
      absl::StrCat("penumbra  ", FormatErrorStats(summary.penumbra)),
      "grey: no receiver on the ray"};
  int text_width = 0;
  for (const std::string& line : lines)
    text_width = std::max(text_width, view::TextWidth(line, text));
  const int map_width = map.width * zoom, map_height = map.height * zoom;
  const int bar_height = 14, line_height = view::TextHeight(text) + 4;
  view::RgbImage image;
  image.width = std::max(map_width, text_width + 2 * margin);
  const int legend_top = map_height + margin;
  image.height = legend_top + bar_height + 4 + line_height + margin +
                 static_cast<int>(lines.size()) * line_height + margin;
  image.rgb.assign(static_cast<size_t>(image.width) * image.height * 3, 24);
  const auto put = [&](int x, int y, const unsigned char rgb[3]) {
    uint8_t* out = &image.rgb[(static_cast<size_t>(y) * image.width + x) * 3];
    out[0] = rgb[0];
    out[1] = rgb[1];
    out[2] = rgb[2];
  };
  const int map_left = (image.width - map_width) / 2;
  for (int y = 0; y < map_height; ++y) {
    for (int x = 0; x < map_width; ++x) {
      const size_t p = static_cast<size_t>(y / zoom) * map.width + x / zoom;
      unsigned char rgb[3];
      const bool known = !std::isnan(map.pdsm[p]) && !std::isnan(map.reference[p]);
      ErrorColour(known ? map.Error(p) : std::nan(""), max_error, rgb);
      put(map_left + x, y, rgb);
    }
  }
  // The colour bar, 0 on the left to max_error (and above) on the right, with three ticks.
  const int bar_left = margin, bar_width = image.width - 2 * margin;
  for (int x = 0; x < bar_width; ++x) {
    unsigned char rgb[3];
    ErrorColour(max_error * x / std::max(1, bar_width - 1), max_error, rgb);
    for (int y = 0; y < bar_height; ++y) put(bar_left + x, legend_top + y, rgb);
  }
  const int tick_y = legend_top + bar_height + 4;
  const std::string mid = absl::StrFormat("%g", max_error / 2),
                    high = absl::StrFormat(">= %g", max_error);
  view::DrawText(&image, bar_left, tick_y, {"0"}, text);
  view::DrawText(&image, bar_left + (bar_width - view::TextWidth(mid, text)) / 2, tick_y, {mid},
                 text);
  view::DrawText(&image, bar_left + bar_width - view::TextWidth(high, text), tick_y, {high}, text);
  view::DrawText(&image, margin, tick_y + line_height + margin, lines, text);
  return view::WritePng(path, image, fs);
}

}  // namespace pdsm
