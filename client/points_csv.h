// Query points: a text file with one "x,y,z" per line (world units). Blank lines and lines
// starting with '#' are skipped, and so is a header row "x,y,z" (any case, any spaces) before
// the first point, as spreadsheets and pandas write it. Errors name the file and line.
#ifndef PDSM_CLIENT_POINTS_CSV_H_
#define PDSM_CLIENT_POINTS_CSV_H_

#include <istream>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "absl/status/statusor.h"

namespace pdsm {

struct QueryPoint {
  glm::dvec3 world;
  std::string text;  // the line's x,y,z as written, echoed in the output
};

// `path` "-" reads standard input (named "stdin" in errors).
absl::StatusOr<std::vector<QueryPoint>> ReadPointsCsv(const std::string& path);

// The same from a stream; `label` names it in errors (the path, for ReadPointsCsv).
absl::StatusOr<std::vector<QueryPoint>> ParsePointsCsv(std::istream& in, const std::string& label);

// Prints "x,y,z,attenuation" on stdout (6 decimals; "nan" when `attenuation` is NaN): the
// output line of `pdsm query` and `pdsm reference`.
void PrintAttenuationLine(const QueryPoint& point, double attenuation);
// "x,y,z,A_1,...,A_n": one column per light.
void PrintAttenuationLine(const QueryPoint& point, std::span<const double> attenuation);

}  // namespace pdsm

#endif  // PDSM_CLIENT_POINTS_CSV_H_
