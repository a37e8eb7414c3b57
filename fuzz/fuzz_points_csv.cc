// The points file of `pdsm query` and `pdsm reference` (client/points_csv.h).
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>

#include "client/points_csv.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  pdsm::ParsePointsCsv(in, "fuzz").status().IgnoreError();
  return 0;
}
