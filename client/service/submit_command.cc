// `pdsm submit SCENE.json --server ADDR`: sends a bake to a coordinator. Mesh files are read
// here and uploaded as content-addressed assets (only those the coordinator lacks); the
// coordinator never sees a path. The job id is the last line on stdout.
#include <cstdio>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "client/bake_overrides.h"
#include "client/cli_common.h"
#include "client/commands.h"
#include "client/service/service_connection.h"
#include "core/assets/mesh_asset.h"
#include "core/scene/mesh_file.h"
#include "core/scene/scene_loader.h"
#include "rpc/grpc_support.h"

namespace pdsm {
namespace {

struct SubmitFlags {
  std::string scene_path;
  ServiceFlags service;
  OverrideFlags overrides;
  int priority = 0;
  std::string idempotency_key;
};

std::string RandomKey() {
  std::random_device random;
  std::string key;
  for (int i = 0; i < 4; ++i) key += absl::StrFormat("%08x", random());
  return key;
}

pdsm::v1::Role ToProtoRole(MeshRole role) {
  switch (role) {
    case MeshRole::kCasterOnly:
      return pdsm::v1::CASTER_ONLY;
    case MeshRole::kReceiverOnly:
      return pdsm::v1::RECEIVER_ONLY;
    case MeshRole::kCasterAndReceiver:
      break;
  }
  return pdsm::v1::CASTER_AND_RECEIVER;
}

// Replaces every mesh path by the SHA-256 of its asset blob; returns the blobs by hash. A file
// whose nodes set roles (core/scene/node_roles.h) becomes one entry per role, in the order
// the local bake splits it (LoadMeshFileByRole), so both bake the same meshes in the same order.
// `entry_of` gets, for each entry sent, the scene file's entry it comes from.
absl::StatusOr<std::map<std::string, std::string>> MeshesToAssets(const std::string& scene_path,
                                                                  pdsm::v1::Scene* scene,
                                                                  std::vector<int>* entry_of) {
  std::map<std::string, std::string> blobs;
  google::protobuf::RepeatedPtrField<pdsm::v1::Mesh> entries;
  for (int i = 0; i < scene->meshes_size(); ++i) {
    const pdsm::v1::Mesh& mesh = scene->meshes(i);
    if (mesh.source_case() != pdsm::v1::Mesh::kPath) {
      *entries.Add() = mesh;
      entry_of->push_back(i);
      continue;
    }
    const std::string context = absl::StrCat(scene_path, ": meshes[", i, "].path");
    absl::StatusOr<std::vector<MeshFileData>> parts =
        LoadMeshFileByRole(ResolveMeshPath(scene_path, mesh.path()), context);
    if (!parts.ok()) return parts.status();
    for (const MeshFileData& part : *parts) {
      for (const std::string& w : part.warnings) {
        std::fprintf(stderr, "pdsm: warning: %s\n", w.c_str());
      }
      std::string blob = EncodeMeshAsset(part);
      std::string sha256 = Sha256Hex(blob);
      pdsm::v1::Mesh& entry = *entries.Add();
      entry = mesh;
      entry.set_asset_sha256(sha256);  // replaces the path (same oneof)
      if (part.node_role.has_value()) entry.set_role(ToProtoRole(*part.node_role));
      entry_of->push_back(i);
      blobs.emplace(std::move(sha256), std::move(blob));
    }
  }
  scene->mutable_meshes()->Swap(&entries);
  return blobs;
}

// An error of the scene as sent names its entry "meshes[k]"; the user's file has entry
// entry_of[k] there (they differ after a file split by roles).
absl::Status NameFileEntry(const absl::Status& error, const std::string& scene_path,
                           const std::vector<int>& entry_of) {
  const std::string message(error.message());
  for (size_t k = 0; k < entry_of.size(); ++k) {
    const std::string sent = absl::StrCat(scene_path, ": meshes[", k, "]");
    if (message.rfind(sent, 0) == 0) {
      return absl::Status(error.code(), absl::StrCat(scene_path, ": meshes[", entry_of[k], "]",
                                                     message.substr(sent.size())));
    }
  }
  return error;
}

absl::Status Upload(const ServiceConnection& c, const std::string& server,
                    const std::map<std::string, std::string>& blobs) {
  pdsm::v1::FindMissingAssetsRequest request;
  for (const auto& [sha256, blob] : blobs) request.add_sha256(sha256);
  pdsm::v1::FindMissingAssetsResponse missing;
  if (grpc::Status s = c.stub->FindMissingAssets(c.Call().get(), request, &missing); !s.ok()) {
    return CallError("finding missing assets", s, server);
  }
  for (const std::string& sha256 : missing.missing_sha256()) {
    const std::string& blob = blobs.at(sha256);
    auto context = c.Call(std::chrono::minutes(30));
    pdsm::v1::UploadAssetResponse response;
    auto writer = c.stub->UploadAsset(context.get(), &response);
    for (size_t offset = 0; offset == 0 || offset < blob.size(); offset += kChunkBytes) {
      pdsm::v1::AssetChunk chunk;
      if (offset == 0) {
        chunk.set_sha256(sha256);
        chunk.set_total_bytes(blob.size());
      }
      chunk.set_data(blob.substr(offset, kChunkBytes));
      if (!writer->Write(chunk)) break;  // the server ended the call: Finish says why
      if (blob.empty()) break;
    }
    writer->WritesDone();
    if (grpc::Status s = writer->Finish(); !s.ok()) {
      return CallError(absl::StrCat("uploading asset ", sha256.substr(0, 12)), s, server);
    }
    std::fprintf(stderr, "uploaded mesh asset %s (%zu bytes)\n", sha256.substr(0, 12).c_str(),
                 blob.size());
  }
  return absl::OkStatus();
}

int RunSubmit(const SubmitFlags& flags) {
  absl::StatusOr<pdsm::v1::BakeParams> overrides = ToBakeParams(flags.overrides);
  if (!overrides.ok()) return ReportError(overrides.status());
  std::vector<std::string> warnings;  // a world file's lights that are not baked
  absl::StatusOr<pdsm::v1::Scene> scene = ParseSceneFile(flags.scene_path, *overrides, &warnings);
  if (!scene.ok()) return ReportError(scene.status());
  for (const std::string& w : warnings) std::fprintf(stderr, "pdsm: warning: %s\n", w.c_str());
  // A scene file may not name assets itself: they are what this command makes of paths.
  for (int i = 0; i < scene->meshes_size(); ++i) {
    if (scene->meshes(i).source_case() == pdsm::v1::Mesh::kAssetSha256) {
      return ReportError(
          absl::InvalidArgumentError(absl::StrCat(flags.scene_path, ": meshes[", i,
                                                  "].assetSha256: mesh assets are only accepted by "
                                                  "the coordinator; use path or inline")));
    }
  }
  std::vector<int> entry_of;
  absl::StatusOr<std::map<std::string, std::string>> blobs =
      MeshesToAssets(flags.scene_path, &*scene, &entry_of);
  if (!blobs.ok()) return ReportError(blobs.status());
  // Validate fully here, from the blobs just made (each mesh file is read once), so errors
  // name the scene file and field before anything is sent.
  const MeshAssetResolver from_blobs = [&](const std::string& sha256, const std::string& context) {
    return DecodeMeshAsset(blobs->at(sha256), context);
  };
  absl::StatusOr<Scene> local =
      SceneFromProto(*scene, flags.scene_path, /*base_dir=*/"", from_blobs);
  if (!local.ok()) return ReportError(NameFileEntry(local.status(), flags.scene_path, entry_of));

  absl::StatusOr<ServiceConnection> connection = Connect(flags.service);
  if (!connection.ok()) return ReportError(connection.status());
  if (absl::Status s = Upload(*connection, flags.service.server, *blobs); !s.ok()) {
    return ReportError(s);
  }
  pdsm::v1::SubmitBakeRequest request;
  request.set_idempotency_key(flags.idempotency_key.empty() ? RandomKey() : flags.idempotency_key);
  request.set_priority(flags.priority);
  *request.mutable_scene() = *std::move(scene);
  pdsm::v1::Job job;
  grpc::Status status;
  // A lost reply is retried with the same key: the coordinator returns the job it made.
  for (int attempt = 0; attempt < 3; ++attempt) {
    status = connection->stub->SubmitBake(connection->Call(std::chrono::minutes(5)).get(), request,
                                          &job);
    if (status.error_code() != grpc::StatusCode::UNAVAILABLE) break;
  }
  if (!status.ok()) {
    return ReportError(CallError("submitting " + flags.scene_path, status, flags.service.server));
  }
  if (job.lights_size() > 1) {
    std::fprintf(stderr, "submitted \"%s\": job %s, %d lights, %d tiles, %s\n",
                 job.scene_name().c_str(), job.job_id().c_str(), job.lights_size(),
                 job.tiles_total(), pdsm::v1::JobState_Name(job.state()).c_str());
  } else {
    std::fprintf(stderr, "submitted \"%s\": job %s, %dx%d, %d samples, %d tiles, %s\n",
                 job.scene_name().c_str(), job.job_id().c_str(), job.width(), job.height(),
                 job.samples(), job.tiles_total(), pdsm::v1::JobState_Name(job.state()).c_str());
  }
  std::printf("%s\n", job.job_id().c_str());
  return kExitOk;
}

}  // namespace

void RegisterSubmitCommand(CLI::App& app, int* exit_code) {
  auto flags = std::make_shared<SubmitFlags>();
  CLI::App* cmd = app.add_subcommand("submit", "Submit a bake to a coordinator");
  cmd->add_option("scene", flags->scene_path, "Scene file (JSON)")->required();
  AddServiceFlags(cmd, &flags->service);
  AddOverrideFlags(cmd, &flags->overrides);
  cmd->add_option("--priority", flags->priority, "Higher runs first, in [-1000, 1000]")
      ->check(CLI::Range(-1000, 1000));
  cmd->add_option("--idempotency-key", flags->idempotency_key,
                  "Resubmitting with the same key returns the same job (default: random)");
  cmd->callback([flags, exit_code] { *exit_code = RunSubmit(*flags); });
}

}  // namespace pdsm
