// The accuracy commands as a user runs them: `pdsm reference` (output format, methods, bad
// input), `pdsm sweep` (CSV columns and rows, error falling with samples, the best one's error
// map) and `pdsm bake --target-error` (the target is met, checked on points of the test's own).
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_split.h"
#include "client/measure/sweep_report.h"
#include "client/view/image_io.h"
#include "core/pdsm/pdsm_file.h"
#include "core/pdsm/pdsm_query.h"
#include "core/reference/accuracy_points.h"
#include "core/reference/exact_visibility.h"
#include "core/scene/scene_loader.h"
#include "tests/test_support.h"

namespace pdsm {
namespace {

using testing::CommandResult;
using testing::ExamplePath;
using testing::ReadBytes;
using testing::RunCommand;
using testing::TempDir;
using testing::WriteText;

const std::string kPdsm = PDSM_CLI;

std::vector<std::string> Lines(const std::string& text) {
  return absl::StrSplit(text, '\n', absl::SkipEmpty());
}

double LastField(const std::string& line) {
  const std::vector<std::string> f = absl::StrSplit(line, ',');
  double value = NAN;
  EXPECT_TRUE(f.back() == "nan" || absl::SimpleAtod(f.back(), &value)) << line;
  return value;
}

TEST(ReferenceCli, ExactAndEmbreeAgreeInQueryFormat) {
  TempDir dir;
  const std::string points = dir.File("pts.csv");
  // Umbra under the upper plate, lit far away, a penumbra point, behind the light (nan).
  WriteText(points, "-1.5,0,-1\n# comment\n9,0,9\n1.4,0,1.2\n0,11,0\n");
  const std::string base = kPdsm + " reference " + ExamplePath("plates") + " --points " + points;
  const CommandResult exact = RunCommand(base + " --method exact", dir);
  ASSERT_EQ(exact.exit_code, 0) << exact.err;
  const CommandResult embree = RunCommand(base + " --method embree --samples 4096", dir);
  ASSERT_EQ(embree.exit_code, 0) << embree.err;
  const std::vector<std::string> a = Lines(exact.out), b = Lines(embree.out);
  ASSERT_EQ(a.size(), 4u) << exact.out;
  ASSERT_EQ(b.size(), 4u) << embree.out;
  EXPECT_EQ(a[0], "-1.5,0,-1,1.000000");
  EXPECT_EQ(a[1], "9,0,9,0.000000");
  EXPECT_EQ(a[3], "0,11,0,nan");
  EXPECT_EQ(b[3], "0,11,0,nan");
  for (size_t k = 0; k < 3; ++k) {
    EXPECT_NEAR(LastField(a[k]), LastField(b[k]), 5 * 0.5 / std::sqrt(4096.0)) << k;
  }
  // auto is exact for a rect light.
  EXPECT_EQ(RunCommand(base, dir).out, exact.out);
}

TEST(ReferenceCli, BadInputExits2NamingTheFile) {
  TempDir dir;
  WriteText(dir.File("pts.csv"), "1,2,3\n1,2\n");
  CommandResult r = RunCommand(
      kPdsm + " reference " + ExamplePath("plates") + " --points " + dir.File("pts.csv"), dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("pts.csv:2"), std::string::npos) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;

  r = RunCommand(
      kPdsm + " reference " + dir.File("missing.json") + " --points " + dir.File("pts.csv"), dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("missing.json"), std::string::npos) << r.err;

  r = RunCommand(
      kPdsm + " reference " + ExamplePath("plates") + " --points " + dir.File("nope.csv"), dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("nope.csv"), std::string::npos) << r.err;

  WriteText(dir.File("ok.csv"), "1,2,3\n");
  r = RunCommand(kPdsm + " reference " + ExamplePath("sun_pillars") + " --points " +
                     dir.File("ok.csv") + " --method exact",
                 dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--method"), std::string::npos) << r.err;
  r = RunCommand(kPdsm + " reference " + ExamplePath("plates") + " --points " + dir.File("ok.csv") +
                     " --method magic",
                 dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--method"), std::string::npos) << r.err;
}

// The weightings (issue #15 item 4): in the umbra and fully lit every definition reads 1 and 0;
// in a penumbra they differ; the flags are checked and named.
TEST(ReferenceCli, WeightingsAgreeOutsidePenumbraeAndDifferInThem) {
  TempDir dir;
  const std::string points = dir.File("pts.csv");
  WriteText(points, "-1.5,0,-1\n9,0,9\n1.0,0,1.2\n");
  const std::string base = kPdsm + " reference " + ExamplePath("plates") + " --points " + points;
  const CommandResult plain = RunCommand(base, dir);
  const CommandResult emitter = RunCommand(base + " --weighting emitter", dir);
  const CommandResult irradiance = RunCommand(base + " --weighting irradiance --normal 0,1,0", dir);
  for (const CommandResult* r : {&plain, &emitter, &irradiance}) {
    ASSERT_EQ(r->exit_code, 0) << r->err;
    const std::vector<std::string> lines = Lines(r->out);
    ASSERT_EQ(lines.size(), 3u) << r->out;
    EXPECT_NEAR(LastField(lines[0]), 1.0, 1e-6);
    EXPECT_EQ(LastField(lines[1]), 0.0);
  }
  EXPECT_NE(emitter.err.find("emitter-weighted"), std::string::npos) << emitter.err;
  const double a = LastField(Lines(plain.out)[2]), e = LastField(Lines(emitter.out)[2]),
               i = LastField(Lines(irradiance.out)[2]);
  EXPECT_GT(a, 0.05);
  EXPECT_LT(a, 0.95);
  EXPECT_GT(std::abs(e - a), 1e-4);
  EXPECT_GT(std::abs(i - e), 1e-4);

  CommandResult r = RunCommand(base + " --weighting irradiance", dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--normal"), std::string::npos) << r.err;
  r = RunCommand(base + " --weighting emitter --normal 0,1,0", dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--normal"), std::string::npos) << r.err;
  r = RunCommand(base + " --weighting cosine", dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--weighting"), std::string::npos) << r.err;
  r = RunCommand(base + " --weighting irradiance --normal 0,0,0", dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("normal"), std::string::npos) << r.err;
}

// Without --weighting the reference measures what the scene bakes (bake.weighting), so that
// `pdsm query` on its bake and `pdsm reference` compare line by line.
TEST(ReferenceCli, TheDefaultWeightingIsTheScenesBake) {
  TempDir dir;
  const std::string points = dir.File("pts.csv");
  WriteText(points, "1.0,0,1.2\n");
  std::string scene = ReadBytes(ExamplePath("plates"));
  const size_t bake = scene.find("\"bake\": {");
  ASSERT_NE(bake, std::string::npos) << scene;
  scene.insert(bake + 9, "\"weighting\": \"EMITTER\", ");
  WriteText(dir.File("scene.json"), scene);
  const std::string base = kPdsm + " reference " + dir.File("scene.json") + " --points " + points;
  const CommandResult by_default = RunCommand(base, dir);
  const CommandResult emitter = RunCommand(base + " --weighting emitter", dir);
  const CommandResult unweighted = RunCommand(base + " --weighting unweighted", dir);
  for (const CommandResult* r : {&by_default, &emitter, &unweighted}) {
    ASSERT_EQ(r->exit_code, 0) << r->err;
  }
  EXPECT_EQ(by_default.out, emitter.out);
  EXPECT_NE(by_default.out, unweighted.out);
}

// column name -> value, for each data row.
std::vector<std::map<std::string, std::string>> ReadCsv(const std::string& path,
                                                        std::string* header) {
  const std::vector<std::string> lines = Lines(ReadBytes(path));
  std::vector<std::map<std::string, std::string>> rows;
  if (lines.empty()) return rows;
  *header = lines[0];
  const std::vector<std::string> names = absl::StrSplit(lines[0], ',');
  for (size_t i = 1; i < lines.size(); ++i) {
    const std::vector<std::string> cells = absl::StrSplit(lines[i], ',');
    EXPECT_EQ(cells.size(), names.size()) << lines[i];
    std::map<std::string, std::string> row;
    for (size_t c = 0; c < std::min(cells.size(), names.size()); ++c) row[names[c]] = cells[c];
    rows.push_back(row);
  }
  return rows;
}

double Number(const std::map<std::string, std::string>& row, const std::string& column) {
  double value = NAN;
  EXPECT_TRUE(absl::SimpleAtod(row.at(column), &value)) << column << "=" << row.at(column);
  return value;
}

TEST(SweepCli, TinyGridWritesCsvAndPlotWithErrorFallingWithSamples) {
  TempDir dir;
  const std::string out = dir.File("sweep");
  const CommandResult r = RunCommand(
      kPdsm + " sweep " + ExamplePath("plates") + " --out " + out +
          " --samples 4,64 --resolution 96 --sm-resolution 384 --epsilon 0.002 --surface-points "
          "400 --free-points 400 --threads 2",
      dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::string header;
  const auto rows = ReadCsv(out + "/sweep.csv", &header);
  EXPECT_EQ(header, SweepCsvHeader());
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0].at("samples"), "4");
  EXPECT_EQ(rows[1].at("samples"), "64");
  for (const auto& row : rows) {
    EXPECT_EQ(row.at("resolution"), "96x96");
    EXPECT_EQ(row.at("sm_resolution"), "384");
    EXPECT_EQ(row.at("surface_n"), "400");
    EXPECT_EQ(row.at("free_n"), "400");
    EXPECT_GT(Number(row, "seconds"), 0.0);
    EXPECT_GT(Number(row, "peak_rss_mib"), 1.0);
    EXPECT_GT(Number(row, "file_bytes"), 0.0);
    EXPECT_LE(Number(row, "surface_mean"), Number(row, "surface_max"));
  }
  // 16x the light samples: the sampling error dominates at 4 samples.
  EXPECT_LT(Number(rows[1], "mean_abs"), Number(rows[0], "mean_abs") / 2);
  EXPECT_LT(Number(rows[1], "surface_mean"), Number(rows[0], "surface_mean"));
  EXPECT_LT(Number(rows[1], "free_mean"), Number(rows[0], "free_mean"));
  // The Pareto mark: a row is on the front exactly when no other row is faster and at least
  // as accurate. (Times within the CSV's rounding of each other cannot be ordered from the
  // file: such a row is not checked.)
  for (size_t a = 0; a < rows.size(); ++a) {
    bool dominated = false, tied = false;
    for (size_t b = 0; b < rows.size(); ++b) {
      if (b == a) continue;
      const double ta = Number(rows[a], "seconds"), tb = Number(rows[b], "seconds");
      const double ea = Number(rows[a], "mean_abs"), eb = Number(rows[b], "mean_abs");
      tied = tied || std::abs(tb - ta) <= 0.002;
      dominated = dominated || (tb < ta && eb <= ea);
    }
    if (!tied) {
      EXPECT_EQ(Number(rows[a], "pareto"), dominated ? 0.0 : 1.0) << "row " << a;
    }
  }
  for (const auto& entry : std::filesystem::directory_iterator(out)) {
    EXPECT_EQ(entry.path().string().find(".tmp"), std::string::npos) << entry.path();
  }
  // The error map of the most accurate configuration (64 samples), and no bake left behind.
  EXPECT_NE(r.out.find("error map of the most accurate configuration (s64"), std::string::npos)
      << r.out;
  absl::StatusOr<view::RgbImage> map = view::ReadPng(out + "/error.png");
  ASSERT_TRUE(map.ok()) << map.status();
  EXPECT_GE(map->width, 96 * 5);  // magnified to about 512 across
  for (const auto& entry : std::filesystem::directory_iterator(out + "/bakes")) {
    EXPECT_NE(entry.path().extension(), ".exr") << entry.path();
  }
  // The reference, computed once: a header and one line per point.
  const std::vector<std::string> reference = Lines(ReadBytes(out + "/reference.csv"));
  ASSERT_EQ(reference.size(), 801u);
  EXPECT_EQ(reference[0], "kind,x,y,z,attenuation");
  if (std::system("command -v gnuplot >/dev/null 2>&1") == 0) {
    EXPECT_GT(std::filesystem::file_size(out + "/sweep.png"), 1000u);
    // --replot redraws it from the CSV alone.
    std::filesystem::remove(out + "/sweep.png");
    const CommandResult replot =
        RunCommand(kPdsm + " sweep " + ExamplePath("plates") + " --out " + out + " --replot", dir);
    EXPECT_EQ(replot.exit_code, 0) << replot.err;
    EXPECT_GT(std::filesystem::file_size(out + "/sweep.png"), 1000u);
  }
}

TEST(SweepCli, WithoutGnuplotWritesTheCsvAndWarns) {
  TempDir dir;
  const std::string out = dir.File("sweep");
  const CommandResult r =
      RunCommand("env PATH=" + dir.File("empty") + " " + kPdsm + " sweep " + ExamplePath("plates") +
                     " --out " + out +
                     " --samples 4 --resolution 48 --sm-resolution 96 --surface-points 50 "
                     "--free-points 50",
                 dir);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("warning: no plot"), std::string::npos) << r.err;
  std::string header;
  EXPECT_EQ(ReadCsv(out + "/sweep.csv", &header).size(), 1u);
  EXPECT_FALSE(std::filesystem::exists(out + "/sweep.png"));
}

TEST(SweepCli, BadKnobExits2) {
  TempDir dir;
  CommandResult r = RunCommand(
      kPdsm + " sweep " + ExamplePath("plates") + " --out " + dir.File("s") + " --sampling NOPE",
      dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--sampling"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("stratified, uniform, sobol, halton, blue-noise"), std::string::npos)
      << r.err;
  r = RunCommand(
      kPdsm + " sweep " + ExamplePath("plates") + " --out " + dir.File("s") + " --resolution 12y5",
      dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--resolution"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir.File("s/sweep.csv")));
}

// Knobs the chooser's bakes cannot take are refused, not silently dropped.
// |pdsm query - exact| of the PDSM at `pdsm_path` over `points` (count 0 when either fails).
ErrorStats ErrorAgainstExact(const Scene& scene, const std::string& pdsm_path,
                             const std::vector<glm::dvec3>& points) {
  absl::StatusOr<std::vector<double>> exact = ExactAttenuation(scene, points);
  absl::StatusOr<PdsmImage> pdsm = ReadPdsm(pdsm_path);
  EXPECT_TRUE(exact.ok()) << exact.status();
  EXPECT_TRUE(pdsm.ok()) << pdsm.status();
  if (!exact.ok() || !pdsm.ok()) return ErrorStats{};
  std::vector<double> baked;
  for (const glm::dvec3& p : points) baked.push_back(QueryAttenuation(*pdsm, p));
  return CompareAttenuation(baked, *exact);
}

TEST(TargetErrorCli, RefusesKnobsItWouldIgnore) {
  TempDir dir;
  for (const std::string flag :
       {"--tile-size 16", "--surfaces-only", "--adaptive-tolerance 0.1", "--samples-per-task 4"}) {
    const CommandResult r = RunCommand(kPdsm + " bake " + ExamplePath("plates") + " -o " +
                                           dir.File("x.exr") + " --target-error 0.02 " + flag,
                                       dir);
    EXPECT_EQ(r.exit_code, 2) << flag << ": " << r.err;
    EXPECT_NE(r.err.find(flag.substr(0, flag.find(' '))), std::string::npos) << r.err;
    EXPECT_FALSE(std::filesystem::exists(dir.File("x.exr")));
  }
}

TEST(TargetErrorCli, BakeMeetsTheTargetOnIndependentPoints) {
  TempDir dir;
  constexpr double kTarget = 0.02;
  const std::string out = dir.File("plates.exr");
  const CommandResult r = RunCommand(
      kPdsm + " bake " + ExamplePath("plates") + " -o " + out + " --target-error 0.02 --threads 2",
      dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("chose samples"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(": met"), std::string::npos) << r.err;
  // Nothing but the PDSM left next to it.
  for (const auto& entry : std::filesystem::directory_iterator(dir.path())) {
    const std::string name = entry.path().filename().string();
    EXPECT_TRUE(name == "plates.exr" || name.rfind("cmd.", 0) == 0) << name;
  }

  // Measured again on points the chooser never saw, against the exact reference.
  absl::StatusOr<Scene> scene = LoadSceneFile(ExamplePath("plates"));
  ASSERT_TRUE(scene.ok());
  absl::StatusOr<AccuracyPoints> points =
      MakeAccuracyPoints(*scene, AccuracyPointCounts{500, 500}, 12345);
  ASSERT_TRUE(points.ok());
  std::vector<glm::dvec3> all = points->surface;
  all.insert(all.end(), points->free_space.begin(), points->free_space.end());
  const ErrorStats e = ErrorAgainstExact(*scene, out, all);
  EXPECT_EQ(e.count, all.size());
  EXPECT_LE(e.mean, kTarget);
  std::printf("target %.3f: independent mean error %.5f\n", kTarget, e.mean);
}

// The issue's case (#15 item 6): a disk light over 30 tilted triangles, where a target met on
// points spread through the frustum missed it twofold just above the ground. The choice is now
// measured on the receivers and the band above them and judged on points it never saw; the
// test draws its own from that region (another seed) and checks E against the exact answer.
TEST(TargetErrorCli, MeetsTheTargetInTheBandAboveTheReceiversOnHeldOutPoints) {
  TempDir dir;
  constexpr double kTarget = 0.01;
  std::string casters;
  uint64_t state = 7;
  const auto next = [&state] {  // a fixed LCG: the same triangles everywhere
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    return static_cast<double>(state >> 11) * 0x1.0p-53;
  };
  for (int k = 0; k < 30; ++k) {
    const glm::dvec3 c(-3 + 6 * next(), 0.5 + 2 * next(), -3 + 6 * next());
    const glm::dvec3 a = glm::normalize(glm::dvec3(next() - 0.5, next() - 0.5, next() - 0.5));
    const glm::dvec3 b = glm::normalize(glm::cross(a, glm::dvec3(next(), 1, next())));
    for (const glm::dvec3& p : {c + 0.5 * a, c - 0.3 * a + 0.4 * b, c - 0.3 * a - 0.4 * b}) {
      absl::StrAppendFormat(&casters, "%s%.6f,%.6f,%.6f", casters.empty() ? "" : ",", p.x, p.y,
                            p.z);
    }
  }
  std::string indices;
  for (int k = 0; k < 90; ++k) absl::StrAppend(&indices, k == 0 ? "" : ",", k);
  const std::string scene_path = dir.File("tilted.json");
  WriteText(scene_path, absl::StrCat(R"({"name": "tilted", "meshes": [
    {"inline": {"positions": [-6,0,-6, 6,0,-6, 6,0,6, -6,0,6], "indices": [0,1,2, 0,2,3]},
     "role": "RECEIVER_ONLY"},
    {"inline": {"positions": [)",
                                     casters, R"(], "indices": [)", indices,
                                     R"(]}, "role": "CASTER_ONLY"}],
    "light": {"disk": {"center": [0,8,0], "normal": [0,-1,0], "radius": 1}}})"));
  const std::string out = dir.File("tilted.exr");
  const CommandResult r = RunCommand(
      kPdsm + " bake " + scene_path + " -o " + out + " --target-error 0.01 --threads 2", dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("mean error on held-out points"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("penumbra only"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(": met"), std::string::npos) << r.err;

  absl::StatusOr<Scene> scene = LoadSceneFile(scene_path);
  ASSERT_TRUE(scene.ok()) << scene.status();
  absl::StatusOr<double> height = DefaultBandHeight(*scene);
  ASSERT_TRUE(height.ok());
  EXPECT_GT(*height, 0.5);  // casters from 0.5 to ~2.9 under a light at 8
  absl::StatusOr<AccuracyPoints> points =
      MakeAccuracyPoints(*scene, AccuracyPointCounts{400, 0, 600, *height}, 4242);
  ASSERT_TRUE(points.ok());
  ASSERT_EQ(points->band.size(), 600u);
  for (const glm::dvec3& p : points->band) {  // above the ground, the one receiver
    EXPECT_GT(p.y, 0.0);
    EXPECT_LE(p.y, *height + 1e-9);
  }
  std::vector<glm::dvec3> all = points->surface;
  all.insert(all.end(), points->band.begin(), points->band.end());
  const ErrorStats e = ErrorAgainstExact(*scene, out, all);
  EXPECT_EQ(e.count, all.size());
  EXPECT_LE(e.mean, kTarget);
  std::printf("target %.3f: mean error on held-out receiver and band points %.5f\n", kTarget,
              e.mean);
}

}  // namespace
}  // namespace pdsm
