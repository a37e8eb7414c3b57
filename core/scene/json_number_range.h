// Finds the first JSON number literal that does not fit a double (1e400, -1e999) and names
// its field. Protobuf's JSON parser refuses such a number with "Number exceeds the range of
// double" and no field; scene files must say which field (docs/scene_format.md).
#ifndef PDSM_CORE_SCENE_JSON_NUMBER_RANGE_H_
#define PDSM_CORE_SCENE_JSON_NUMBER_RANGE_H_

#include <optional>
#include <string>
#include <string_view>

namespace pdsm {

struct OutOfRangeNumber {
  std::string field;    // e.g. "meshes[0].inline.positions[11]"
  std::string literal;  // the number as written
};

// Walks the JSON text (objects, arrays, strings, literals) tracking the field path. nullopt
// when every number fits, or when the text is not well-formed JSON (the real parser reports
// that).
std::optional<OutOfRangeNumber> FindOutOfRangeNumber(std::string_view json);

}  // namespace pdsm

#endif  // PDSM_CORE_SCENE_JSON_NUMBER_RANGE_H_
