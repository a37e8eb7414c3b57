#include "client/measure/target_error.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iterator>
#include <limits>
#include <optional>
#include <vector>

#include "absl/strings/ascii.h"
#include "absl/strings/str_format.h"
#include "client/measure/child_bake.h"
#include "core/scene/scene_loader.h"

namespace pdsm {
namespace {

constexpr int kPilotSamples = 8;
constexpr int kPilotResolution = 64;
constexpr double kMargin = 1.25;
constexpr uint64_t kPointsSeed = 1;
constexpr uint64_t kHeldOutSeed = 2;
constexpr int kSampleCounts[] = {1, 2, 4, 8, 16, 32, 64, 128, 256, 512, 1024, 2048, 4096, 8192};
constexpr int kResolutions[] = {32, 48, 64, 96, 128, 192, 256, 384, 512, 768, 1024, 1536, 2048};

// e(N, R) = sqrt((a N^-k)^2 + (b (R/R0)^-m)^2): sampling and resolution errors are independent,
// so they add in quadrature, not linearly. t(N, R) = f + g N (R / R0)^beta.
struct Model {
  double a = 0, k = 0.5, b = 0, m = 1;
  double f = 0, g = 0, beta = 2;
  int r0 = kPilotResolution;  // the resolution b and g were measured at

  double Sampling(int n) const { return a * std::pow(n, -k); }
  double Resolution(int r) const { return b * std::pow(static_cast<double>(r) / r0, -m); }
  double Error(int n, int r) const { return std::hypot(Sampling(n), Resolution(r)); }
  double Cost(int n, int r) const {
    return f + g * n * std::pow(static_cast<double>(r) / r0, beta);
  }
};

struct Measurement {
  BakeKnobs knobs;
  double seconds = 0;
  BakeErrors errors;
};

class TargetErrorSearch {
 public:
  TargetErrorSearch(const TargetErrorOptions& options, const Scene& scene, BakeKnobs base,
                    const AccuracyProbe& probe)
      : options_(options), scene_(scene), base_(std::move(base)), probe_(probe) {}

  BakeKnobs KnobsFor(int n, int r) const {
    BakeKnobs k = base_;
    k.samples = options_.samples.value_or(n);
    if (options_.resolution) {
      k.width = options_.resolution->first;
      k.height = options_.resolution->second;
    } else {
      k.width = r;
      k.height = std::max(1, static_cast<int>(std::lround(static_cast<double>(r) *
                                                          scene_.bake.height / scene_.bake.width)));
    }
    k.sm_resolution =
        options_.sm_resolution.value_or(std::min(2 * k.width, kMaxShadowMapResolution));
    k.epsilon = options_.epsilon.value_or(options_.target / 4);
    if (options_.depth_bias) k.depth_bias = options_.depth_bias;
    return k;
  }

  absl::StatusOr<Measurement> Bake(const BakeKnobs& knobs, const std::string& path) {
    std::vector<std::string> args = knobs.BakeArgs();
    if (options_.threads > 0)
      args.insert(args.end(), {"--threads", std::to_string(options_.threads)});
    absl::StatusOr<ChildBakeResult> bake =
        RunChildBake(options_.scene_path, path, args, path + ".log");
    if (!bake.ok()) return bake.status();
    absl::StatusOr<BakeErrors> errors = probe_.Measure(path);
    if (!errors.ok()) return errors.status();
    ++bakes_;
    std::fprintf(stderr, "  %-40s %7.2fs  mean error %.5f\n", knobs.Label().c_str(), bake->seconds,
                 errors->all.mean);
    return Measurement{knobs, bake->seconds, *errors};
  }

  // The pilots, then the fit. A knob the user fixed is piloted at its value only.
  absl::StatusOr<Model> FitModel(const std::filesystem::path& dir) {
    const int n0 = options_.samples.value_or(kPilotSamples);
    const int r0 = options_.resolution ? options_.resolution->first : kPilotResolution;
    // N0, 4 N0, 16 N0 at R0: the sampling term. Then 4 N0 at 2 R0: the resolution term, where
    // sampling noise hides it less than at N0 and the pilot still costs little.
    const int nq = options_.samples ? n0 : 4 * n0;
    std::vector<std::pair<int, int>> pilots = {{n0, r0}};
    if (!options_.samples) pilots.insert(pilots.end(), {{nq, r0}, {16 * n0, r0}});
    if (!options_.resolution) pilots.push_back({nq, 2 * r0});
    std::vector<Measurement> m;
    for (const auto& [n, r] : pilots) {
      absl::StatusOr<Measurement> pilot =
          Bake(KnobsFor(n, r), (dir / absl::StrFormat("pilot_%d_%d.exr", n, r)).string());
      if (!pilot.ok()) return pilot.status();
      m.push_back(*pilot);
    }
    auto e2 = [&](size_t i) { return m[i].errors.all.mean * m[i].errors.all.mean; };
    Model model;
    model.r0 = r0;
    // Sampling: squared errors along N differ only by the sampling term.
    const size_t at_nq = options_.samples ? 0 : 1;  // the pilot at (nq, R0)
    if (!options_.samples) {
      const double d1 = e2(0) - e2(1), d2 = e2(1) - e2(2);
      if (d1 > 0 && d2 > 0 && d2 < d1) {
        // At least N^-1/2: no sampling pattern converges slower than independent samples.
        model.k = std::clamp(-std::log(d2 / d1) / (2 * std::log(4.0)), 0.5, 1.5);
      }
      if (d1 > 0) {
        model.a = std::sqrt(d1 / (std::pow(n0, -2 * model.k) * (1 - std::pow(4.0, -2 * model.k))));
      }
    }
    // Resolution: what sampling leaves at (nq, R0) and (nq, 2 R0). Kept at >= 1/4 of the
    // measured error so that R stays in play when sampling seems to explain everything.
    const double s2 = model.Sampling(nq) * model.Sampling(nq);
    const double q0 = std::sqrt(std::max(e2(at_nq) - s2, e2(at_nq) / 16));
    model.b = q0;
    if (!options_.resolution) {
      const double q1 = std::sqrt(std::max(0.0, e2(m.size() - 1) - s2));
      model.m = q1 > 0 && q0 > q1 ? std::clamp(std::log2(q0 / q1), 0.25, 2.0) : 0.25;
    } else {
      model.m = 0;  // R is not chosen
    }
    FitCost(m, n0, nq, &model);
    std::fprintf(stderr,
                 "target-error: model e(N,R) = sqrt((%.4g N^-%.2f)^2 + (%.4g (R/%d)^-%.2f)^2), "
                 "t(N,R) = %.2f + %.4g N (R/%d)^%.2f s\n",
                 model.a, model.k, model.b, model.r0, model.m, model.f, model.g, model.r0,
                 model.beta);
    return model;
  }

  // Time per sample from the N series (a floor of 5 % of the first pilot keeps timing noise
  // on tiny scenes from making samples look free). beta stays 2: every sample scans R^2 rays
  // and rasterizes a shadow map of (2R)^2 texels. Fitting it from the pilots failed: at 64^2
  // and 128^2 their times are mostly process start-up, the fit gave beta = 1, and the chosen
  // 768^2 bake took 10x its predicted time (plates, E = 0.005).
  void FitCost(const std::vector<Measurement>& m, int n0, int /*nq*/, Model* model) const {
    const double t1 = m[0].seconds;
    model->g = 0.05 * t1 / n0;
    if (!options_.samples) model->g = std::max(model->g, (m[2].seconds - t1) / (15.0 * n0));
    if (options_.samples) model->g = t1 / n0;
    model->f = std::max(0.0, t1 - model->g * n0);
    model->beta = 2;
  }

  // The cheapest (N, R) predicted to meet target / demand and costing more than `above`; nullopt
  // when none is. *predicted: the most accurate prediction seen (for messages).
  std::optional<std::pair<int, int>> Choose(const Model& model, double demand, double above,
                                            double* predicted, double* cost) const {
    std::vector<int> ns, rs;
    if (options_.samples)
      ns = {*options_.samples};
    else
      ns.assign(std::begin(kSampleCounts), std::end(kSampleCounts));
    if (options_.resolution)
      rs = {options_.resolution->first};
    else
      rs.assign(std::begin(kResolutions), std::end(kResolutions));
    std::optional<std::pair<int, int>> best;
    *cost = std::numeric_limits<double>::infinity();
    *predicted = std::numeric_limits<double>::infinity();
    double lowest = std::numeric_limits<double>::infinity();
    for (int n : ns) {
      for (int r : rs) {
        const double e = model.Error(n, r), t = model.Cost(n, r);
        if (t <= above) continue;
        lowest = std::min(lowest, e);
        if (e * demand <= options_.target / kMargin && t < *cost) {
          best = std::make_pair(n, r), *cost = t, *predicted = e;
        }
      }
    }
    if (!best) *predicted = lowest;
    return best;
  }

  int bakes() const { return bakes_; }

 private:
  const TargetErrorOptions& options_;
  const Scene& scene_;
  const BakeKnobs base_;
  const AccuracyProbe& probe_;
  int bakes_ = 0;
};

}  // namespace

absl::StatusOr<TargetErrorResult> BakeToTargetError(const TargetErrorOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  absl::StatusOr<Scene> scene = LoadSceneFile(options.scene_path);
  if (scene.ok()) scene = OneLight(*std::move(scene), "", "pdsm bake --target-error");
  if (!scene.ok()) return scene.status();
  if (scene->light.is_sphere_face()) {
    // It would tune and bake one face: the others need their own points.
    return absl::InvalidArgumentError(
        absl::StrCat(options.scene_path,
                     ": light: --target-error does not take a sphere light yet; bake it "
                     "with chosen knobs (pdsm compare --light NAME@+x measures a face against the "
                     "true sphere)"));
  }
  // The pattern is a knob too: --sampling, else the scene's (whose default is the measured
  // best, Sobol; docs/accuracy.md, "Sampling patterns").
  std::string sampling = options.sampling;
  if (sampling.empty()) {
    absl::StatusOr<std::string> scene_sampling = SceneSamplingName(options.scene_path);
    if (!scene_sampling.ok()) return scene_sampling.status();
    sampling = absl::AsciiStrToLower(*scene_sampling);
  }
  BakeKnobs base = KnobsFromScene(*scene, sampling);
  const AccuracyPointCounts counts{options.surface_points, 0, options.band_points,
                                   options.band_height};
  // The reference of the definition the bakes store (bake.weighting).
  ReferenceOptions reference;
  reference.weighting.kind = scene->bake.weighting;
  absl::StatusOr<AccuracyProbe> probe =
      AccuracyProbe::Create(*scene, counts, kPointsSeed, reference);
  if (!probe.ok()) return probe.status();
  absl::StatusOr<AccuracyProbe> held_out =
      AccuracyProbe::Create(*scene, counts, kHeldOutSeed, reference);
  if (!held_out.ok()) return held_out.status();
  std::fprintf(stderr,
               "target-error %g: reference (%s) on %zu receiver + %zu band points (band %.4g "
               "high), twice (fit, held out), in %.1fs; pilots:\n",
               options.target, ReferenceMethodName(probe->method()), probe->points().surface.size(),
               probe->points().band.size(), probe->points().band_height,
               probe->reference_seconds() + held_out->reference_seconds());

  const std::filesystem::path pilots = options.output_path + ".pilots";
  std::error_code ec;
  std::filesystem::create_directories(pilots, ec);
  if (ec) return absl::InternalError(absl::StrFormat("%s: %s", pilots.string(), ec.message()));
  TargetErrorSearch search(options, *scene, base, *probe);
  absl::StatusOr<Model> model = search.FitModel(pilots);
  std::filesystem::remove_all(pilots, ec);
  if (!model.ok()) return model.status();

  TargetErrorResult result;
  double demand = 1.0, above = -1.0;
  for (int attempt = 0; attempt <= kMaxRebakes; ++attempt) {
    double predicted = 0, cost = 0;
    const std::optional<std::pair<int, int>> choice =
        search.Choose(*model, demand, above, &predicted, &cost);
    if (!choice) {
      if (attempt > 0) break;  // output_path holds the last (missed) bake
      return absl::InvalidArgumentError(absl::StrFormat(
          "--target-error %g: no configuration up to %d samples and %d pixels across is "
          "predicted to reach it (best predicted %.5f); ask for a larger error",
          options.target, kSampleCounts[std::size(kSampleCounts) - 1],
          kResolutions[std::size(kResolutions) - 1], predicted));
    }
    const BakeKnobs knobs = search.KnobsFor(choice->first, choice->second);
    std::fprintf(stderr, "target-error: bake %s (predicted error %.5f, %.1fs)\n",
                 knobs.Label().c_str(), predicted, cost);
    absl::StatusOr<Measurement> m = search.Bake(knobs, options.output_path);
    if (!m.ok()) return m.status();
    result.knobs = knobs;
    result.predicted = predicted;
    absl::StatusOr<BakeErrors> check = held_out->Measure(options.output_path);
    if (!check.ok()) return check.status();
    result.measured = m->errors;
    result.held_out = *check;
    result.band_height = probe->points().band_height;
    result.seconds = m->seconds;
    std::fprintf(stderr, "  held out: mean error %.5f\n", check->all.mean);
    result.met = check->all.mean <= options.target;
    if (result.met) break;
    // Missed: the model was optimistic by this much; ask for that much more, and costlier.
    demand *= 1.1 * check->all.mean / options.target;
    above = cost;
  }
  std::filesystem::remove(options.output_path + ".log", ec);
  result.bakes = search.bakes();
  result.total_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace pdsm
