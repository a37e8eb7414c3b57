#include "client/sweep_report.h"

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"

namespace pdsm {
namespace {

std::string ErrorCells(const ErrorStats& e) {
  return absl::StrFormat("%d,%.6f,%.6f,%.6f", e.count, e.mean, e.p95, e.max);
}

std::string RowCells(const SweepRow& row) {
  const BakeKnobs& k = row.knobs;
  return absl::StrCat(
      absl::StrFormat("%s,%d,%dx%d,%d,%g,%s,%s,", k.Label(), k.samples, k.width, k.height,
                      k.sm_resolution, k.epsilon, k.sampling,
                      k.depth_bias ? absl::StrFormat("%g", *k.depth_bias) : "auto"),
      absl::StrFormat("%.3f,%.1f,%d,%.6f,", row.bake.seconds, row.bake.peak_rss_bytes / 1048576.0,
                      row.bake.file_bytes, row.errors.all.mean),
      ErrorCells(row.errors.surface), ",", ErrorCells(row.errors.free_space), ",",
      row.pareto ? 1 : 0);
}

bool OnPath(const std::string& program) {
  const char* path = std::getenv("PATH");
  if (path == nullptr) return false;
  for (absl::string_view dir : absl::StrSplit(path, ':')) {
    if (dir.empty()) continue;
    std::error_code ec;
    if (std::filesystem::exists(std::filesystem::path(std::string(dir)) / program, ec)) {
      return true;
    }
  }
  return false;
}

// Doubles quotes for a gnuplot single-quoted string.
std::string GnuplotQuote(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("''") : std::string(1, c);
  return out + "'";
}

std::string ShellQuote(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

}  // namespace

std::string SweepCsvHeader() {
  return "config,samples,resolution,sm_resolution,epsilon,sampling,depth_bias,"
         "seconds,"
         "peak_rss_mib,file_bytes,mean_abs,surface_n,surface_mean,surface_p95,"
         "surface_max,"
         "free_n,free_mean,free_p95,free_max,pareto";
}

void MarkParetoFront(std::vector<SweepRow>* rows) {
  for (SweepRow& a : *rows) {
    a.pareto = true;
    for (const SweepRow& b : *rows) {
      const bool no_worse =
          b.bake.seconds <= a.bake.seconds && b.errors.all.mean <= a.errors.all.mean;
      const bool better = b.bake.seconds < a.bake.seconds || b.errors.all.mean < a.errors.all.mean;
      if (&a != &b && no_worse && better) {
        a.pareto = false;
        break;
      }
    }
  }
}

absl::Status WriteSweepCsv(const std::string& path, const std::vector<SweepRow>& rows) {
  const std::string temp = path + ".tmp";
  {
    std::ofstream out(temp, std::ios::trunc);
    out << SweepCsvHeader() << "\n";
    for (const SweepRow& row : rows) out << RowCells(row) << "\n";
    out.flush();
    if (!out) return absl::InternalError(absl::StrFormat("%s: write failed", temp));
  }
  std::error_code ec;
  std::filesystem::rename(temp, path, ec);
  if (ec) return absl::InternalError(absl::StrFormat("%s: %s", path, ec.message()));
  return absl::OkStatus();
}

absl::Status PlotSweep(const std::vector<SweepRow>& rows, const std::string& csv_path,
                       const std::string& png_path, const std::string& title) {
  if (!OnPath("gnuplot")) return absl::NotFoundError("gnuplot is not installed");
  const std::string temp_png = png_path + ".tmp";
  const std::string script_path = png_path + ".gp";
  std::vector<const SweepRow*> front;
  for (const SweepRow& row : rows) {
    if (row.pareto) front.push_back(&row);
  }
  std::sort(front.begin(), front.end(),
            [](const SweepRow* a, const SweepRow* b) { return a->bake.seconds < b->bake.seconds; });
  {
    // CSV columns 8 (seconds) and 11 (mean_abs). Log-log: both follow power laws.
    std::ofstream script(script_path, std::ios::trunc);
    script << "$front << EOD\n";
    for (const SweepRow* row : front) {
      script << absl::StrFormat("%.6g,%.6g\n", row->bake.seconds, row->errors.all.mean);
    }
    script << "EOD\n"
           << "set terminal png size 900,600\n"
           << "set output " << GnuplotQuote(temp_png) << "\n"
           << "set datafile separator ','\n"
           << "set key top right\n"
           << "set logscale xy\n"
           << "set grid\n"
           << "set title " << GnuplotQuote(title) << " noenhanced\n"
           << "set xlabel 'bake time (s)'\n"
           << "set ylabel 'mean |attenuation error| (surface + free space)'\n"
           << "plot " << GnuplotQuote(csv_path)
           << " skip 1 using 8:11 with points pt 7 ps 1.2 title 'configurations', \\\n"
           << "     $front using 1:2 with linespoints lw 2 pt 6 ps 2 title 'Pareto front', \\\n"
           << "     " << GnuplotQuote(csv_path)
           << " skip 1 using 8:11:(sprintf('%d', $2)) with labels offset 0,1 font ',8' "
              "notitle\n";
  }
  const std::string command = absl::StrCat("gnuplot ", ShellQuote(script_path), " 1>&2");
  const int status = std::system(command.c_str());
  if (status != 0) {
    return absl::InternalError(
        absl::StrFormat("gnuplot %s failed (status %d)", script_path, status));
  }
  std::error_code ec;
  std::filesystem::rename(temp_png, png_path, ec);
  if (ec) return absl::InternalError(absl::StrFormat("%s: %s", png_path, ec.message()));
  std::filesystem::remove(script_path, ec);
  return absl::OkStatus();
}

}  // namespace pdsm
