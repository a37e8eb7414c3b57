// The scene file: JSON parse, overrides, and the whole validation of the message (mesh files
// are refused, as on the coordinator: the fuzzer must not wander the file system).
#include <cstddef>
#include <cstdint>

#include "core/scene/scene_loader.h"
#include "fuzz/fuzz_input_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const pdsm::fuzz::InputFile file(data, size);
  if (!file.ok()) return 0;
  absl::StatusOr<pdsm::v1::Scene> message = pdsm::ParseSceneFile(file.path());
  if (!message.ok()) return 0;
  pdsm::SceneFromProto(*message, "fuzz", /*base_dir=*/"").status().IgnoreError();
  return 0;
}
