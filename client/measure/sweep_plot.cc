#include "client/measure/sweep_plot.h"

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <vector>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"
#include "client/measure/gnuplot.h"
#include "client/measure/sweep_report.h"
#include "core/util/atomic_file.h"

namespace pdsm {
namespace {

using CsvRow = std::map<std::string, std::string>;

// The knob columns and how a label spells them.
constexpr std::pair<const char*, const char*> kKnobs[] = {
    {"samples", "N"}, {"resolution", "R"}, {"sm_resolution", "SM"},
    {"epsilon", "e"}, {"sampling", ""},    {"depth_bias", "b"}};

bool OnPath(const std::string& program) {
  const char* path = std::getenv("PATH");
  if (path == nullptr) return false;
  for (absl::string_view dir : absl::StrSplit(path, ':')) {
    std::error_code ec;
    if (!dir.empty() &&
        std::filesystem::exists(std::filesystem::path(std::string(dir)) / program, ec)) {
      return true;
    }
  }
  return false;
}

// A gnuplot single-quoted string. Control characters become spaces: a newline would end the
// command, and the title comes from the scene file ("x\n!rm ..." must stay text).
std::string GnuplotQuote(const std::string& s) {
  std::string out = "'";
  for (char c : s) {
    if (c == '\'') {
      out += "''";
    } else {
      out += static_cast<unsigned char>(c) < 0x20 || c == 0x7f ? ' ' : c;
    }
  }
  return out + "'";
}

absl::StatusOr<std::vector<CsvRow>> ReadSweepCsv(const std::string& path) {
  std::ifstream in(path);
  if (!in) return absl::NotFoundError(absl::StrFormat("%s: cannot open", path));
  std::string line;
  if (!std::getline(in, line) || line != SweepCsvHeader()) {
    return absl::InvalidArgumentError(absl::StrFormat("%s:1: not a sweep's header", path));
  }
  const std::vector<std::string> names = absl::StrSplit(line, ',');
  std::vector<CsvRow> rows;
  double number = 0;
  for (int line_number = 2; std::getline(in, line); ++line_number) {
    const std::vector<std::string> cells = absl::StrSplit(line, ',');
    if (cells.size() != names.size() || !absl::SimpleAtod(cells[7], &number) ||
        !absl::SimpleAtod(cells[10], &number)) {
      return absl::InvalidArgumentError(
          absl::StrFormat("%s:%d: expected %d cells", path, line_number, names.size()));
    }
    CsvRow row;
    for (size_t c = 0; c < names.size(); ++c) row[names[c]] = cells[c];
    rows.push_back(std::move(row));
  }
  return rows;
}

double Number(const CsvRow& row, const std::string& column) {
  double value = 0;
  (void)absl::SimpleAtod(row.at(column), &value);
  return value;
}

// "N64 R256x256": the knobs whose value differs between rows.
std::vector<std::string> Labels(const std::vector<CsvRow>& rows, std::string* legend) {
  std::vector<std::pair<const char*, const char*>> varying;
  for (const auto& knob : kKnobs) {
    for (const CsvRow& row : rows) {
      if (row.at(knob.first) != rows.front().at(knob.first)) {
        varying.push_back(knob);
        break;
      }
    }
  }
  std::vector<std::string> labels;
  for (const CsvRow& row : rows) {
    std::vector<std::string> parts;
    for (const auto& [column, prefix] : varying) parts.push_back(prefix + row.at(column));
    labels.push_back(absl::StrJoin(parts, " "));
  }
  std::vector<std::string> names;
  for (const auto& [column, prefix] : varying) names.push_back(column);
  *legend = names.empty() ? "one configuration" : "labels: " + absl::StrJoin(names, ", ");
  return labels;
}

// The gnuplot script; the PNG goes to gnuplot's stdout.
std::string Script(const std::vector<CsvRow>& rows, const std::string& title) {
  std::ostringstream script;
  std::string legend;
  const std::vector<std::string> labels = Labels(rows, &legend);
  script << "$all << EOD\n";
  for (size_t i = 0; i < rows.size(); ++i) {
    script << absl::StrFormat("%s %s \"%s\"\n", rows[i].at("seconds"), rows[i].at("mean_abs"),
                              labels[i]);
  }
  std::vector<const CsvRow*> front;
  for (const CsvRow& row : rows) {
    if (row.at("pareto") == "1") front.push_back(&row);
  }
  std::sort(front.begin(), front.end(), [](const CsvRow* a, const CsvRow* b) {
    return Number(*a, "seconds") < Number(*b, "seconds");
  });
  script << "EOD\n$front << EOD\n";
  for (const CsvRow* row : front)
    script << row->at("seconds") << " " << row->at("mean_abs") << "\n";
  // Log-log: error and time both follow power laws of the knobs.
  script << "EOD\n"
         << "set terminal png size 900,600\n"
         << "set output\n"  // stdout
         << "set key top right\n"
         << "set logscale xy\n"
         << "set grid\n"
         << "set title " << GnuplotQuote(title + " (" + legend + ")") << " noenhanced\n"
         << "set xlabel 'bake time (s)'\n"
         << "set ylabel 'mean |attenuation error| (surface + free space)'\n"
         << "plot $all using 1:2 with points pt 7 ps 1.2 title 'configurations', \\\n"
         << "     $front using 1:2 with linespoints lw 2 pt 6 ps 2 title 'Pareto front', \\\n"
         << "     $all using 1:2:3 with labels offset 0,1 font ',8' noenhanced notitle\n";
  return script.str();
}

}  // namespace

absl::Status PlotSweep(const std::string& csv_path, const std::string& png_path,
                       const std::string& title, FileSystem* fs) {
  if (!OnPath("gnuplot")) return absl::NotFoundError("gnuplot is not installed");
  absl::StatusOr<std::vector<CsvRow>> rows = ReadSweepCsv(csv_path);
  if (!rows.ok()) return rows.status();
  absl::StatusOr<std::string> png = RunGnuplot(Script(*rows, title));
  if (!png.ok()) return png.status();
  return WriteFileAtomically(png_path, *png, fs);
}

}  // namespace pdsm
