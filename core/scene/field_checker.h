// Checks of single scene fields with the error messages every part of the scene validation
// shares: INVALID_ARGUMENT "SOURCE: FIELD: what (got VALUE)", FIELD spelled with the JSON names
// the user wrote (e.g. "examples/plates/scene.json: meshes[1].transform[3]: must be finite
// (got NaN)"). Internal to core/scene (not a public API); see scene_loader.h for that.
#ifndef PDSM_CORE_SCENE_FIELD_CHECKER_H_
#define PDSM_CORE_SCENE_FIELD_CHECKER_H_

#include <cstdint>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <google/protobuf/repeated_field.h>
#include <glm/glm.hpp>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/string_view.h"

namespace pdsm::internal {

using RepeatedDoubles = google::protobuf::RepeatedField<double>;

// Shortest text that reads back to the same double, with the JSON spellings of the
// non-finite values (NaN, Infinity, -Infinity) so the message shows what the user wrote.
std::string FormatDouble(double x);
// "[1, 2.5, NaN]".
std::string FormatDoubles(const RepeatedDoubles& values);
// "field[index]".
std::string Indexed(absl::string_view field, int index);

// The field checks of one scene message. Each returns OK or the INVALID_ARGUMENT error for
// `field`; a bake field whose value came from the overrides is marked " (override)". Immutable
// after construction, so safe to share between threads.
class FieldChecker {
 public:
  // `source` prefixes every message (the scene file, or a label such as "job 7").
  // `overridden`: the JSON names of the bake fields the overrides replaced ("samples").
  FieldChecker(std::string source, std::set<std::string> overridden)
      : source_(std::move(source)), overridden_(std::move(overridden)) {}

  const std::string& source() const { return source_; }

  // The same checks for a field that the checks' code spells `from` but the user wrote as
  // `to`: a field "from.x" or "from[1]" is named "to.x", "to[1]" (the checks of `light` and
  // `bake` serve each entry of `lights`, as "lights[2]" and "lights[2].bake"). Renames chain,
  // the newest first: a checker renamed "light" -> "lights[2]" and then "light.disk" ->
  // "light.spot" names "light.disk.radius" "lights[2].spot.radius". Override marks follow the
  // spelling of the code ("bake.samples").
  FieldChecker Renamed(std::string from, std::string to) const {
    FieldChecker copy = *this;
    copy.renames_.emplace_back(std::move(from), std::move(to));
    return copy;
  }

  // "SOURCE: FIELD[ (override)]: what".
  absl::Status Error(absl::string_view field, absl::string_view what) const {
    return absl::InvalidArgumentError(
        absl::StrCat(source_, ": ", UserSpelling(field), OverrideMark(field), ": ", what));
  }

  absl::Status CheckFinite(absl::string_view field, double x) const;
  // Each value finite; an error names the element ("field[2]").
  absl::Status CheckAllFinite(absl::string_view field, const RepeatedDoubles& values) const;
  // Finite and > 0.
  absl::Status CheckPositive(absl::string_view field, double x) const;
  // In [1, max].
  absl::Status CheckUintRange(absl::string_view field, uint32_t value, int max) const;
  // Exactly 3 finite numbers.
  absl::StatusOr<glm::dvec3> Vec3(absl::string_view field, const RepeatedDoubles& values) const;
  // 3 finite numbers, not all zero, normalized.
  absl::StatusOr<glm::dvec3> Direction(absl::string_view field,
                                       const RepeatedDoubles& values) const;

 private:
  // " (override)" when a bake field's value came from the overrides, not from the file.
  absl::string_view OverrideMark(absl::string_view field) const;
  // `field` with each rename whose `from` is a whole leading component of it applied, newest
  // first.
  std::string UserSpelling(absl::string_view field) const;

  std::string source_;
  std::set<std::string> overridden_;
  std::vector<std::pair<std::string, std::string>> renames_;  // (from, to), oldest first
};

}  // namespace pdsm::internal

#endif  // PDSM_CORE_SCENE_FIELD_CHECKER_H_
