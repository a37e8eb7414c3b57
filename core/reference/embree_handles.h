// Owning handles of Embree 3 objects, so that every early return releases them.
#ifndef PDSM_CORE_REFERENCE_EMBREE_HANDLES_H_
#define PDSM_CORE_REFERENCE_EMBREE_HANDLES_H_

#include <memory>

#include <embree3/rtcore.h>

namespace pdsm {

struct EmbreeDeviceDeleter {
  void operator()(RTCDeviceTy* d) const { rtcReleaseDevice(d); }
};
struct EmbreeSceneDeleter {
  void operator()(RTCSceneTy* s) const { rtcReleaseScene(s); }
};

using EmbreeDevice = std::unique_ptr<RTCDeviceTy, EmbreeDeviceDeleter>;
using EmbreeScene = std::unique_ptr<RTCSceneTy, EmbreeSceneDeleter>;

}  // namespace pdsm

#endif  // PDSM_CORE_REFERENCE_EMBREE_HANDLES_H_
