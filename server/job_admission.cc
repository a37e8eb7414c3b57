#include "server/job_admission.h"

#include <algorithm>
#include <random>

#include <google/protobuf/io/coded_stream.h>
#include <google/protobuf/wire_format_lite.h>

#include "absl/base/thread_annotations.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/synchronization/mutex.h"
#include "core/scene/scene_loader.h"

namespace pdsm {

absl::Status CheckSubmitRequest(const pdsm::v1::SubmitBakeRequest& request) {
  const std::string& key = request.idempotency_key();
  if (key.empty() || key.size() > 128) {
    return absl::InvalidArgumentError(
        absl::StrCat("idempotency_key: must have 1 to 128 characters (got ", key.size(), ")"));
  }
  for (char c : key) {
    if (c < 0x21 || c > 0x7e) {
      return absl::InvalidArgumentError("idempotency_key: must be printable ASCII, no spaces");
    }
  }
  if (request.priority() < -1000 || request.priority() > 1000) {
    return absl::InvalidArgumentError(
        absl::StrCat("priority: must be in [-1000, 1000] (got ", request.priority(), ")"));
  }
  return absl::OkStatus();
}

absl::StatusOr<BakePlan> PlanJobScene(const pdsm::v1::Scene& scene, const std::string& label,
                                      const CoordinatorAssets& assets,
                                      const AdmissionLimits* limits) {
  // Asset triangles are counted as they decode, to stop early on a huge scene; the final
  // check counts every mesh (inline ones too) once.
  int64_t asset_triangles = 0;
  absl::StatusOr<Scene> loaded =
      SceneFromProto(scene, label, /*base_dir=*/"",
                     assets.Resolver(limits ? limits->max_triangles : 0, &asset_triangles));
  if (!loaded.ok()) return loaded.status();
  if (loaded->LightCount() > 1) {
    return absl::UnimplementedError(absl::StrFormat(
        "%s: lights: %d lights; the service bakes one light per job so far: bake the scene "
        "locally (`pdsm bake`), or submit a scene per light",
        label, loaded->LightCount()));
  }
  if (limits != nullptr) {
    int64_t triangles = 0;
    for (const TriangleMesh& m : loaded->meshes) triangles += m.indices.size() / 3;
    const int64_t pixels = int64_t{loaded->bake.width} * loaded->bake.height;
    if (pixels > limits->max_job_pixels) {
      return absl::ResourceExhaustedError(absl::StrFormat(
          "%s: bake.resolution: %dx%d is %d pixels, above this coordinator's limit of %d", label,
          loaded->bake.width, loaded->bake.height, pixels, limits->max_job_pixels));
    }
    const int tile = std::max(1, loaded->bake.tile_size);
    const int64_t tiles = ((int64_t{loaded->bake.width} + tile - 1) / tile) *
                          ((int64_t{loaded->bake.height} + tile - 1) / tile);
    if (tiles > limits->max_job_tiles) {
      return absl::ResourceExhaustedError(absl::StrFormat(
          "%s: bake.tileSize: %d makes %d tiles of the %dx%d PDSM, above this coordinator's "
          "limit of %d (a larger tileSize)",
          label, loaded->bake.tile_size, tiles, loaded->bake.width, loaded->bake.height,
          limits->max_job_tiles));
    }
    if (loaded->bake.samples > limits->max_samples) {
      return absl::ResourceExhaustedError(
          absl::StrFormat("%s: bake.samples: %d is above this coordinator's limit of %d", label,
                          loaded->bake.samples, limits->max_samples));
    }
    if (triangles > limits->max_triangles) {
      return absl::ResourceExhaustedError(
          absl::StrFormat("%s: meshes: %d triangles, above this coordinator's limit of %d", label,
                          triangles, limits->max_triangles));
    }
  }
  return PlanBake(*loaded);
}

absl::StatusOr<JobRecord> NewJobRecord(const pdsm::v1::SubmitBakeRequest& request,
                                       const BakePlan& plan, int64_t now_unix_ms) {
  JobRecord record;
  record.job_id = RandomHex(8);
  record.idempotency_key = request.idempotency_key();
  record.scene_name = request.scene().name();
  record.state = pdsm::v1::QUEUED;
  record.priority = request.priority();
  record.tiles_total = static_cast<int>(plan.tiles.size());
  record.samples_total = int64_t{plan.header.samples} * record.tiles_total;
  record.created_unix_ms = record.updated_unix_ms = now_unix_ms;
  record.width = plan.geometry().width;
  record.height = plan.geometry().height;
  record.samples = plan.header.samples;
  if (!request.scene().SerializeToString(&record.scene)) {
    return absl::InternalError("cannot serialize the scene");
  }
  return record;
}

absl::StatusOr<pdsm::v1::BakeParams> JobBakeParams(const std::string& serialized_scene,
                                                   const std::string& label) {
  using google::protobuf::internal::WireFormatLite;
  // Only Scene.light (3), Scene.bake (4) and Scene.lights (5) are parsed; the meshes (which
  // may be large inline arrays) are skipped by length.
  constexpr int kLightField = 3, kBakeField = 4, kLightsField = 5;
  google::protobuf::io::CodedInputStream in(
      reinterpret_cast<const uint8_t*>(serialized_scene.data()),
      static_cast<int>(serialized_scene.size()));
  pdsm::v1::Scene scene;
  const absl::Status corrupt =
      absl::DataLossError(absl::StrCat(label, ": stored scene is corrupt"));
  while (const uint32_t tag = in.ReadTag()) {
    const int field = WireFormatLite::GetTagFieldNumber(tag);
    const bool wanted = field == kLightField || field == kBakeField || field == kLightsField;
    if (!wanted ||
        WireFormatLite::GetTagWireType(tag) != WireFormatLite::WIRETYPE_LENGTH_DELIMITED) {
      if (!WireFormatLite::SkipField(&in, tag)) return corrupt;
      continue;
    }
    uint32_t length = 0;
    if (!in.ReadVarint32(&length)) return corrupt;
    const auto limit = in.PushLimit(static_cast<int>(length));
    google::protobuf::MessageLite* target =
        field == kLightField    ? static_cast<google::protobuf::MessageLite*>(scene.mutable_light())
        : field == kLightsField ? static_cast<google::protobuf::MessageLite*>(scene.add_lights())
                                : scene.mutable_bake();
    if (!target->MergeFromCodedStream(&in) || !in.ConsumedEntireMessage()) return corrupt;
    in.PopLimit(limit);
  }
  if (!in.ConsumedEntireMessage()) return corrupt;
  return EffectiveBakeParams(scene, label);
}

std::string RandomHex(int bytes) {
  static absl::Mutex mu(absl::kConstInit);
  static std::random_device device ABSL_GUARDED_BY(mu);
  absl::MutexLock lock(&mu);
  std::string out;
  for (int i = 0; i < bytes; ++i) out += absl::StrFormat("%02x", device() & 0xff);
  return out;
}

}  // namespace pdsm
