// FNV-1a, 64 bits: the checksum of the coordinator's stored tiles (core/pipeline/tile_file.h)
// and of their log's record frames (server/tile_log.h). Catches torn and damaged bytes, not
// forgery.
#ifndef PDSM_CORE_UTIL_FNV1A_H_
#define PDSM_CORE_UTIL_FNV1A_H_

#include <cstdint>
#include <string_view>

namespace pdsm {

inline uint64_t Fnv1a64(std::string_view bytes) {
  uint64_t hash = 0xcbf29ce484222325ull;
  for (const char c : bytes) {
    hash ^= static_cast<unsigned char>(c);
    hash *= 0x100000001b3ull;
  }
  return hash;
}

}  // namespace pdsm

#endif  // PDSM_CORE_UTIL_FNV1A_H_
