#include "client/points_csv.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>

#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"
#include "absl/strings/strip.h"

namespace pdsm {

namespace {

bool IsHeaderRow(const std::vector<absl::string_view>& fields) {
  static constexpr absl::string_view kNames[3] = {"x", "y", "z"};
  if (fields.size() != 3) return false;
  for (size_t k = 0; k < 3; ++k) {
    if (!absl::EqualsIgnoreCase(absl::StripAsciiWhitespace(fields[k]), kNames[k])) return false;
  }
  return true;
}

}  // namespace

absl::StatusOr<std::vector<QueryPoint>> ReadPointsCsv(const std::string& path) {
  if (path == "-") return ParsePointsCsv(std::cin, "stdin");
  std::ifstream in(path);
  if (!in) return absl::NotFoundError(absl::StrFormat("%s: cannot open points file", path));
  return ParsePointsCsv(in, path);
}

absl::StatusOr<std::vector<QueryPoint>> ParsePointsCsv(std::istream& in, const std::string& path) {
  std::vector<QueryPoint> points;
  bool header_seen = false;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    const absl::string_view text = absl::StripAsciiWhitespace(line);
    if (text.empty() || text[0] == '#') continue;
    std::vector<absl::string_view> fields = absl::StrSplit(text, ',');
    if (points.empty() && !header_seen && IsHeaderRow(fields)) {
      header_seen = true;
      continue;
    }
    double xyz[3];
    bool ok = fields.size() == 3;
    for (size_t k = 0; ok && k < 3; ++k) {
      fields[k] = absl::StripAsciiWhitespace(fields[k]);
      ok = absl::SimpleAtod(fields[k], &xyz[k]) && std::isfinite(xyz[k]);
    }
    if (!ok) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "%s:%d: expected three finite numbers \"x,y,z\", got \"%s\"", path, number, text));
    }
    points.push_back(QueryPoint{{xyz[0], xyz[1], xyz[2]}, absl::StrJoin(fields, ",")});
  }
  return points;
}

void PrintAttenuationLine(const QueryPoint& point, double attenuation) {
  PrintAttenuationLine(point, std::span<const double>(&attenuation, 1));
}

void PrintAttenuationLine(const QueryPoint& point, std::span<const double> attenuation) {
  std::string line = point.text;
  for (double a : attenuation) {
    if (std::isnan(a)) {
      line += ",nan";
    } else {
      absl::StrAppendFormat(&line, ",%.6f", a);
    }
  }
  line += '\n';
  std::fputs(line.c_str(), stdout);
}

}  // namespace pdsm
