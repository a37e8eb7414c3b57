#include "server/job_admission.h"

#include <algorithm>
#include <memory>
#include <optional>
#include <random>

#include <google/protobuf/io/coded_stream.h>
#include <google/protobuf/wire_format_lite.h>

#include "absl/base/thread_annotations.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/synchronization/mutex.h"
#include "core/bake/plan_fingerprint.h"
#include "core/bake/plan_memory.h"
#include "core/pipeline/bake_engine.h"
#include "core/scene/scene.h"
#include "core/scene/scene_loader.h"
#include "core/scene/sphere_faces.h"

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

namespace {

// Within `limits`: the pixels and samples of one light's bake. `label` names the light.
absl::Status CheckLightLimits(const BakeSettings& bake, const std::string& label,
                              const AdmissionLimits& limits) {
  const int64_t pixels = int64_t{bake.width} * bake.height;
  if (pixels > limits.max_job_pixels) {
    return absl::ResourceExhaustedError(
        absl::StrFormat("%s: bake.resolution: %dx%d is %d pixels, above this coordinator's "
                        "limit of %d",
                        label, bake.width, bake.height, pixels, limits.max_job_pixels));
  }
  if (bake.samples > limits.max_samples) {
    return absl::ResourceExhaustedError(
        absl::StrFormat("%s: bake.samples: %d is above this coordinator's limit of %d", label,
                        bake.samples, limits.max_samples));
  }
  return absl::OkStatus();
}

// The scene's lights and bake, without its meshes (skipped by length: they may be large
// inline arrays).
absl::StatusOr<pdsm::v1::Scene> ReadSceneLights(const std::string& serialized_scene,
                                                const std::string& label) {
  using google::protobuf::internal::WireFormatLite;
  // Only Scene.light (3), Scene.bake (4) and Scene.lights (5) are parsed.
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
  return scene;
}

int64_t SceneHeldBytes(const pdsm::v1::Scene& scene) {
  // Parsed (StoredJob::scene) and serialized (JobRecord::scene).
  return static_cast<int64_t>(scene.SpaceUsedLong() + scene.ByteSizeLong());
}

// The plan's groups with a tile a caster may reach: the engine lists only those
// (core/pipeline/bake_engine.cc, SchedulerSpec).
int64_t GroupsWithWork(const BakePlan& plan) {
  if (plan.tile_has_casters.empty()) return plan.group_count();
  int64_t groups = 0;
  for (int g = 0; g < plan.group_count(); ++g) {
    const std::vector<int> tiles = plan.group(g).tiles;
    groups += std::any_of(tiles.begin(), tiles.end(),
                          [&plan](int t) { return plan.tile_has_casters[t]; });
  }
  return groups;
}

absl::Status PlannedBytesError(const std::string& label, const char* what, int64_t bytes,
                               int64_t max_bytes, bool surfaces_only) {
  return absl::ResourceExhaustedError(absl::StrFormat(
      "%s: its plans %s %.1f MiB in this coordinator, above its limit of %.1f MiB "
      "(--max-planned-mib): fewer tiles (a larger bake.tileSize)%s, or fewer lights per job",
      label, what, static_cast<double>(bytes) / double{1 << 20},
      static_cast<double>(max_bytes) / double{1 << 20},
      surfaces_only ? ", bake.surfacesOnly off (it keeps the receivers for every light)" : ""));
}

// Within `max_bytes`: a lower bound of the job's JobHeldBytes, from its lights' settings and
// its receiving meshes' sizes, before anything is planned. (PlanJobLights checks the exact
// bytes as it plans.)
absl::Status CheckMinPlannedBytes(const pdsm::v1::Scene& scene, const Scene& loaded,
                                  const std::string& label, int64_t max_bytes) {
  int64_t receiver_vertices = 0, receiver_triangles = 0;
  for (const TriangleMesh& m : loaded.meshes) {
    if (!Receives(m.role)) continue;
    receiver_vertices += static_cast<int64_t>(m.positions_world.size());
    receiver_triangles += static_cast<int64_t>(m.indices.size() / 3);
  }
  int64_t bytes = SceneHeldBytes(scene);
  bool surfaces_only = false;
  for (size_t i = 0; i < loaded.LightCount(); ++i) {
    const BakeSettings bake = LightOf(loaded, i).bake;
    surfaces_only = surfaces_only || bake.surfaces_only;
    bytes += MinReleasedPlanBytes(bake, receiver_vertices, receiver_triangles) +
             BakeEngine::JobHeldBytes(TileCountOf(bake), /*groups=*/1, /*groups_with_work=*/0);
  }
  if (bytes <= max_bytes) return absl::OkStatus();
  return PlannedBytesError(label, "would hold at least", bytes, max_bytes, surfaces_only);
}

}  // namespace

int64_t LightHeldBytes(const BakePlan& plan) {
  return PlanHeldBytes(plan) + BakeEngine::JobHeldBytes(static_cast<int64_t>(plan.tile_count()),
                                                        plan.group_count(), GroupsWithWork(plan));
}

int64_t JobHeldBytes(const std::vector<PlannedLight>& plans, const pdsm::v1::Scene& scene) {
  int64_t bytes = SceneHeldBytes(scene);
  for (const PlannedLight& light : plans) bytes += LightHeldBytes(*light.plan);
  return bytes;
}

absl::StatusOr<std::vector<PlannedLight>> PlanJobLights(const pdsm::v1::Scene& scene,
                                                        const std::string& label,
                                                        const CoordinatorAssets& assets,
                                                        const AdmissionLimits* limits) {
  // Asset triangles are counted as they decode, to stop early on a huge scene; the final
  // check counts every mesh (inline ones too) once.
  int64_t asset_triangles = 0;
  absl::StatusOr<Scene> loaded =
      SceneFromProto(scene, label, /*base_dir=*/"",
                     assets.Resolver(limits ? limits->max_triangles : 0, &asset_triangles));
  if (!loaded.ok()) return loaded.status();
  const size_t count = loaded->LightCount();
  if (limits != nullptr) {
    int64_t triangles = 0;
    for (const TriangleMesh& m : loaded->meshes) triangles += m.indices.size() / 3;
    // Checked before anything is planned: a 1 KB request must not make the coordinator plan
    // millions of tiles (8192^2 at tile size 1 took 87 s and 5 GB).
    int64_t tiles = 0;
    for (size_t i = 0; i < count; ++i) {
      const SceneLight light = LightOf(*loaded, i);
      const std::string light_label =
          count == 1 ? label : absl::StrFormat("%s: lights[%d] \"%s\"", label, i, light.name);
      if (absl::Status s = CheckLightLimits(light.bake, light_label, *limits); !s.ok()) return s;
      tiles += TileCountOf(light.bake);
      if (tiles > limits->max_job_tiles) {
        return absl::ResourceExhaustedError(absl::StrFormat(
            "%s: bake.tileSize: %d makes %d tiles%s, above this coordinator's limit of %d (a "
            "larger tileSize%s)",
            light_label, light.bake.tile_size, tiles,
            count == 1 ? absl::StrFormat(" of the %dx%d PDSM", light.bake.width, light.bake.height)
                       : std::string(" with the lights before it"),
            limits->max_job_tiles, count == 1 ? "" : ", or fewer lights per job"));
      }
    }
    if (triangles > limits->max_triangles) {
      return absl::ResourceExhaustedError(
          absl::StrFormat("%s: meshes: %d triangles, above this coordinator's limit of %d", label,
                          triangles, limits->max_triangles));
    }
    if (absl::Status s = CheckMinPlannedBytes(scene, *loaded, label, limits->max_planned_bytes);
        !s.ok()) {
      return s;
    }
  }
  std::vector<PlannedLight> plans;
  plans.reserve(count);
  int64_t held_bytes = SceneHeldBytes(scene);
  // One index of the world's triangles serves every light's plan.
  absl::StatusOr<std::shared_ptr<const SceneIndex>> index = SceneIndex::Build(*loaded);
  if (!index.ok()) return index.status();
  for (size_t i = 0; i < count; ++i) {
    // A one-light scene is planned as it stands (its light may have no name).
    absl::StatusOr<BakePlan> plan = count == 1 ? PlanBake(**index) : PlanBake(**index, i);
    if (!plan.ok()) return plan.status();
    std::string fingerprint = PlanFingerprint(*plan);
    ReleaseRenderGeometry(&*plan);
    held_bytes += LightHeldBytes(*plan);
    if (limits != nullptr && held_bytes > limits->max_planned_bytes) {
      return PlannedBytesError(label, count == 1 ? "hold" : "hold (with the lights before it)",
                               held_bytes, limits->max_planned_bytes, plan->header.surfaces_only);
    }
    plans.push_back(
        PlannedLight{std::make_shared<const BakePlan>(*std::move(plan)), std::move(fingerprint)});
  }
  return plans;
}
absl::StatusOr<PlannedLight> PlanJobLightLevel(const pdsm::v1::Scene& scene,
                                               const std::string& label,
                                               const CoordinatorAssets& assets, int light,
                                               const BakePlan& base,
                                               std::shared_ptr<const RefinedPixels> refined) {
  int64_t asset_triangles = 0;  // counted by the resolver; admission checked them already
  absl::StatusOr<Scene> loaded =
      SceneFromProto(scene, label, /*base_dir=*/"", assets.Resolver(0, &asset_triangles));
  if (!loaded.ok()) return loaded.status();
  absl::StatusOr<std::shared_ptr<const SceneIndex>> index = SceneIndex::Build(*loaded);
  if (!index.ok()) return index.status();
  // A one-light scene is planned as it stands, as PlanJobLights plans it.
  const std::optional<size_t> which =
      loaded->LightCount() == 1 ? std::nullopt : std::optional<size_t>(light);
  absl::StatusOr<BakePlan> plan = PlanRefinementLevel(**index, which, base, std::move(refined));
  if (!plan.ok()) return plan.status();
  std::string fingerprint = PlanFingerprint(*plan);
  ReleaseRenderGeometry(&*plan);
  return PlannedLight{std::make_shared<const BakePlan>(*std::move(plan)), std::move(fingerprint)};
}

absl::StatusOr<JobRecord> NewJobRecord(const pdsm::v1::SubmitBakeRequest& request,
                                       const std::vector<PlannedLight>& lights,
                                       int64_t now_unix_ms) {
  JobRecord record;
  record.job_id = RandomHex(8);
  record.idempotency_key = request.idempotency_key();
  record.scene_name = request.scene().name();
  record.state = pdsm::v1::QUEUED;
  record.priority = request.priority();
  for (const PlannedLight& light : lights) {
    const int tiles = light.plan->tile_count();
    record.tiles_total += tiles;
    record.samples_total += int64_t{light.plan->header.samples} * tiles;
  }
  record.created_unix_ms = record.updated_unix_ms = now_unix_ms;
  const BakePlan& first = *lights.at(0).plan;
  record.width = first.geometry().width;
  record.height = first.geometry().height;
  record.samples = first.header.samples;
  if (!request.scene().SerializeToString(&record.scene)) {
    return absl::InternalError("cannot serialize the scene");
  }
  return record;
}

absl::StatusOr<std::vector<JobLightSize>> JobLightSizes(const std::string& serialized_scene,
                                                        const std::string& label) {
  absl::StatusOr<pdsm::v1::Scene> scene = ReadSceneLights(serialized_scene, label);
  if (!scene.ok()) return scene.status();
  std::vector<JobLightSize> sizes;
  const int count = std::max(1, scene->lights_size());
  for (int i = 0; i < count; ++i) {
    absl::StatusOr<pdsm::v1::BakeParams> bake = EffectiveBakeParams(*scene, label, i);
    if (!bake.ok()) return bake.status();
    const pdsm::v1::Light& light = scene->lights_size() > 0 ? scene->lights(i) : scene->light();
    JobLightSize size;
    size.name = light.name();
    size.width = static_cast<int>(bake->resolution(0));
    size.height = static_cast<int>(bake->resolution(1));
    size.samples = static_cast<int>(bake->samples());
    const int tile = std::max<int>(1, static_cast<int>(bake->tile_size()));
    size.tiles = ((size.width + tile - 1) / tile) * ((size.height + tile - 1) / tile);
    size.bake = *std::move(bake);
    if (!light.has_sphere()) {
      sizes.push_back(std::move(size));
      continue;
    }
    // A sphere bakes as its faces, each a light of the job (core/scene/sphere_faces.h).
    for (const SphereFace& face : SphereFaces()) {
      JobLightSize face_size = size;
      face_size.name = SphereFaceName(light.name(), face);
      sizes.push_back(std::move(face_size));
    }
  }
  return sizes;
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
