#include "core/scene/field_checker.h"

#include <algorithm>
#include <charconv>
#include <cmath>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"

namespace pdsm::internal {

std::string FormatDouble(double x) {
  if (std::isnan(x)) return "NaN";
  if (std::isinf(x)) return x > 0 ? "Infinity" : "-Infinity";
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), x);
  return std::string(buffer, result.ptr);
}

std::string FormatDoubles(const RepeatedDoubles& values) {
  return absl::StrCat(
      "[",
      absl::StrJoin(values, ", ", [](std::string* out, double x) { out->append(FormatDouble(x)); }),
      "]");
}

std::string Indexed(absl::string_view field, int index) {
  return absl::StrCat(field, "[", index, "]");
}

absl::string_view FieldChecker::OverrideMark(absl::string_view field) const {
  constexpr absl::string_view kBake = "bake.";
  if (field.substr(0, kBake.size()) != kBake) return "";
  absl::string_view name = field.substr(kBake.size());
  name = name.substr(0, name.find_first_of(".["));
  return overridden_.count(std::string(name)) ? " (override)" : "";
}

std::string FieldChecker::UserSpelling(absl::string_view field) const {
  std::string spelt(field);
  for (auto it = renames_.rbegin(); it != renames_.rend(); ++it) {
    const auto& [from, to] = *it;
    if (absl::string_view(spelt).substr(0, from.size()) != from) continue;
    const std::string rest = spelt.substr(from.size());
    if (rest.empty() || rest[0] == '.' || rest[0] == '[') spelt = absl::StrCat(to, rest);
  }
  return spelt;
}

absl::Status FieldChecker::CheckFinite(absl::string_view field, double x) const {
  if (std::isfinite(x)) return absl::OkStatus();
  return Error(field, absl::StrCat("must be finite (got ", FormatDouble(x), ")"));
}

absl::Status FieldChecker::CheckAllFinite(absl::string_view field,
                                          const RepeatedDoubles& values) const {
  for (int i = 0; i < values.size(); ++i) {
    if (absl::Status s = CheckFinite(Indexed(field, i), values[i]); !s.ok()) return s;
  }
  return absl::OkStatus();
}

absl::Status FieldChecker::CheckPositive(absl::string_view field, double x) const {
  if (absl::Status s = CheckFinite(field, x); !s.ok()) return s;
  if (x > 0) return absl::OkStatus();
  return Error(field, absl::StrCat("must be > 0 (got ", FormatDouble(x), ")"));
}

absl::Status FieldChecker::CheckUintRange(absl::string_view field, uint32_t value, int max) const {
  if (value >= 1 && value <= static_cast<uint32_t>(max)) return absl::OkStatus();
  return Error(field, absl::StrCat("must be in [1, ", max, "] (got ", value, ")"));
}

absl::StatusOr<glm::dvec3> FieldChecker::Vec3(absl::string_view field,
                                              const RepeatedDoubles& values) const {
  if (values.size() != 3) {
    return Error(field, absl::StrCat("must have 3 numbers (got ", values.size(), ")"));
  }
  if (absl::Status s = CheckAllFinite(field, values); !s.ok()) return s;
  return glm::dvec3(values[0], values[1], values[2]);
}

// Divides by the largest component first so that neither 1e-200 nor 1e200 components
// underflow or overflow in the length.
absl::StatusOr<glm::dvec3> FieldChecker::Direction(absl::string_view field,
                                                   const RepeatedDoubles& values) const {
  absl::StatusOr<glm::dvec3> v = Vec3(field, values);
  if (!v.ok()) return v.status();
  const double scale = std::max({std::abs(v->x), std::abs(v->y), std::abs(v->z)});
  if (scale == 0) {
    return Error(field, absl::StrCat("must be non-zero (got ", FormatDoubles(values), ")"));
  }
  return glm::normalize(*v / scale);
}

}  // namespace pdsm::internal
