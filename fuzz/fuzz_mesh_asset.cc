// A mesh asset blob (core/assets/mesh_asset.h), as a client uploads it.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "core/assets/mesh_asset.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  pdsm::DecodeMeshAsset(bytes, "fuzz").status().IgnoreError();
  return 0;
}
