// The PDSM reader (docs/pdsm_format.md): our bounded pre-read (single-part and multipart
// framing), the header checksums, then OpenEXR. Every light of a valid file is also queried
// at a few points.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/pdsm/pdsm_file.h"
#include "core/pdsm/pdsm_query.h"
#include "fuzz/fuzz_input_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const pdsm::fuzz::InputFile file(data, size);
  if (!file.ok()) return 0;
  pdsm::ReadPdsmHeader(file.path()).status().IgnoreError();
  pdsm::ReadPdsmHeaders(file.path()).status().IgnoreError();
  absl::StatusOr<std::vector<pdsm::PdsmImage>> lights = pdsm::ReadPdsmLights(file.path());
  if (!lights.ok()) return 0;
  for (const pdsm::PdsmImage& image : *lights) {
    for (const glm::dvec3 p :
         {glm::dvec3(0, 0, 0), glm::dvec3(1, -2, 3), glm::dvec3(0.5, 0, 1e3)}) {
      (void)pdsm::QueryAttenuation(image, p);
    }
  }
  return 0;
}
