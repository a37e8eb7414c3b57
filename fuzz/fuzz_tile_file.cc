// A stored tile (core/pipeline/tile_file.h), as FetchTile sends it and a restarted
// coordinator reads it.
#include <cstddef>
#include <cstdint>
#include <string>

#include "core/pipeline/tile_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  pdsm::DecodeTileFile(bytes, "fuzz").status().IgnoreError();
  return 0;
}
