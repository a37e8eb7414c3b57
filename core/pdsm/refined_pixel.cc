#include "core/pdsm/refined_pixel.h"

#include <cmath>
#include <limits>
#include <utility>

#include "absl/strings/str_format.h"

namespace pdsm {
namespace {

std::string OrdinaryFault(std::span<const Vertex> f) {
  for (size_t k = 0; k < f.size(); ++k) {
    if (std::isnan(f[k].z) || (k > 0 && f[k].z < f[k - 1].z)) {
      return absl::StrFormat("vertex depths are not nondecreasing (vertex %d)", k);
    }
  }
  return "";
}

// The first of the f * f + 1 ends of a refined pixel with samples[1].z bands.
size_t FirstEnd(std::span<const Vertex> samples) {
  return 2 + 2 * static_cast<size_t>(samples[1].z);
}

}  // namespace

std::span<const Vertex> RefinedFunction(std::span<const Vertex> samples, int f, size_t m) {
  const size_t ends = FirstEnd(samples);
  const size_t base = ends + 1 + static_cast<size_t>(f) * f;
  const size_t begin = m == 0 ? 0 : static_cast<size_t>(samples[ends + m - 1].z);
  const size_t end = static_cast<size_t>(samples[ends + m].z);
  return samples.subspan(base + begin, end - begin);
}

bool RefinedAt(std::span<const Vertex> samples, double z) {
  if (RefinementOf(samples) == 1) return false;
  const size_t bands = static_cast<size_t>(samples[1].z);
  for (size_t k = 0; k < bands; ++k) {
    if (samples[2 + 2 * k].z <= z && z <= samples[3 + 2 * k].z) return true;
  }
  return false;
}

void AppendRefinedPixel(int f, std::span<const RefinedBand> bands, std::span<const Vertex> own,
                        std::span<const std::vector<Vertex>> subs, std::vector<Vertex>* out) {
  out->push_back(Vertex{static_cast<float>(f * f), static_cast<float>(-f)});
  out->push_back(Vertex{static_cast<float>(bands.size()), -1.0f});
  for (const RefinedBand& b : bands) {
    out->push_back(Vertex{b.lo, -1.0f});
    out->push_back(Vertex{b.hi, -1.0f});
  }
  size_t end = own.size();
  out->push_back(Vertex{static_cast<float>(end), -1.0f});
  for (const std::vector<Vertex>& sub : subs) {
    end += sub.size();
    out->push_back(Vertex{static_cast<float>(end), -1.0f});
  }
  out->insert(out->end(), own.begin(), own.end());
  for (const std::vector<Vertex>& sub : subs) out->insert(out->end(), sub.begin(), sub.end());
}

std::string PixelFunctionFault(std::span<const Vertex> samples, int max_refinement) {
  if (max_refinement <= 1 || samples.empty() || !(samples[0].a <= -2.0f)) {
    return OrdinaryFault(samples);
  }
  const float marker = -samples[0].a;
  const int f = static_cast<int>(marker);
  if (static_cast<float>(f) != marker || !IsRefinementFactor(f) || f > max_refinement) {
    return absl::StrFormat("a refinement of %g (the file's largest is %d)", marker, max_refinement);
  }
  const size_t subs = static_cast<size_t>(f) * f;
  if (samples.size() < 2 || samples[0].z != static_cast<float>(subs) || samples[1].a != -1.0f ||
      !(samples[1].z >= 1) || samples[1].z != std::floor(samples[1].z) ||
      samples[1].z > static_cast<float>(samples.size())) {
    return absl::StrFormat("a %dx refined pixel without its band count", f);
  }
  const size_t ends = FirstEnd(samples);
  if (samples.size() < ends + subs + 1) {
    return absl::StrFormat("a %dx refined pixel without its bands and %d function ends", f,
                           subs + 1);
  }
  for (size_t k = 2; k < ends; ++k) {
    if (samples[k].a != -1.0f || std::isnan(samples[k].z) ||
        (k > 2 && !(samples[k].z >= samples[k - 1].z))) {
      return absl::StrFormat("band %d is not in order", (k - 2) / 2);
    }
  }
  const size_t vertices = samples.size() - ends - subs - 1;
  float previous = 0;
  for (size_t m = 0; m <= subs; ++m) {
    const float end = samples[ends + m].z;
    if (samples[ends + m].a != -1.0f || !(end >= previous) || end != std::floor(end) ||
        end > static_cast<float>(vertices)) {
      return absl::StrFormat("function %d's end (%g) is not in order within %d vertices", m, end,
                             vertices);
    }
    previous = end;
  }
  if (previous != static_cast<float>(vertices)) {
    return absl::StrFormat("the functions end at vertex %g of %d", previous, vertices);
  }
  if (std::string fault = OrdinaryFault(RefinedFunction(samples, f, 0)); !fault.empty()) {
    return absl::StrFormat("its own function: %s", fault);
  }
  for (int j = 0; j < f; ++j) {
    for (int i = 0; i < f; ++i) {
      if (std::string fault = OrdinaryFault(SubFunction(samples, f, i, j)); !fault.empty()) {
        return absl::StrFormat("sub-pixel (%d, %d): %s", i, j, fault);
      }
    }
  }
  return "";
}

double SubPixelAttenuation(std::span<const Vertex> samples, int f, int i, int j, double z) {
  const std::span<const Vertex> sub = SubFunction(samples, f, i, j);
  return sub.empty() ? std::numeric_limits<double>::quiet_NaN() : EvaluateAttenuation(sub, z);
}

double LatticeAttenuation(std::span<const Vertex> samples, int f, int i, int j, double z,
                          bool* sub_defined) {
  if (sub_defined != nullptr) *sub_defined = false;
  const int g = RefinementOf(samples);
  if (g == 1) return EvaluateAttenuation(samples, z);
  const std::span<const Vertex> own = RefinedFunction(samples, g, 0);
  if (g > f || !RefinedAt(samples, z)) return EvaluateAttenuation(own, z);
  const double a = SubPixelAttenuation(samples, g, i * g / f, j * g / f, z);
  if (std::isnan(a)) return EvaluateAttenuation(own, z);
  if (sub_defined != nullptr) *sub_defined = true;
  return a;
}

double EvaluatePixelCentre(std::span<const Vertex> samples, double z) {
  const int f = RefinementOf(samples);
  if (f == 1) return EvaluateAttenuation(samples, z);
  const int a = f / 2 - 1, b = f / 2;
  bool defined = false, sub = false;
  double sum = 0;
  for (const auto& [i, j] : {std::pair{a, a}, std::pair{b, a}, std::pair{a, b}, std::pair{b, b}}) {
    sum += LatticeAttenuation(samples, f, i, j, z, &sub);
    defined = defined || sub;
  }
  return defined ? 0.25 * sum : EvaluateAttenuation(RefinedFunction(samples, f, 0), z);
}

}  // namespace pdsm
