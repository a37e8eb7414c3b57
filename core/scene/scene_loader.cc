// Reading a scene file: the text, the JSON parse into pdsm.v1.Scene and the overrides. The
// validation of the message into a Scene is SceneBuilder's (scene_builder.h).
#include "core/scene/scene_loader.h"

#include <filesystem>
#include <fstream>
#include <optional>
#include <set>
#include <sstream>
#include <system_error>
#include <utility>
#include <vector>

#include <google/protobuf/util/json_util.h>
#include <spdlog/spdlog.h>

#include "absl/status/status.h"
#include "absl/strings/escaping.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "absl/strings/string_view.h"
#include "core/scene/file_lights.h"
#include "core/scene/json_number_range.h"
#include "core/scene/scene_bake.h"
#include "core/scene/scene_builder.h"
#include "core/scene/scene_mesh.h"
#include "core/scene/world_file.h"

namespace pdsm {
namespace {

using internal::ResolveAgainst;
using internal::SceneBuilder;

// The folder relative mesh paths of a scene file resolve against ("." for a bare file name,
// since an empty base_dir means "no mesh files").
std::string SceneFolder(const std::string& scene_path) {
  const std::filesystem::path folder = std::filesystem::path(scene_path).parent_path();
  return folder.empty() ? std::string(".") : folder.string();
}

// Every field set in `overrides` replaces the scene's (a repeated field as a whole, the
// frustum as a whole), and the same field of every light's own `bake`: a command-line flag
// wins over both. Returns the JSON names of the replaced fields, for messages.
std::set<std::string> ApplyOverrides(const pdsm::v1::BakeParams& overrides,
                                     pdsm::v1::Scene* scene) {
  std::set<std::string> names;
  *scene->mutable_bake() = internal::MergedBakeParams(scene->bake(), overrides, &names);
  if (scene->has_light() && scene->light().has_bake()) {
    internal::ClearBakeFields(names, scene->mutable_light()->mutable_bake());
  }
  for (pdsm::v1::Light& light : *scene->mutable_lights()) {
    if (light.has_bake()) internal::ClearBakeFields(names, light.mutable_bake());
  }
  return names;
}

// Protobuf reports a syntax error on three lines: the message, the text around the error and
// a caret under it. One line reads better on a terminal and in logs.
std::string OneLineJsonError(absl::string_view message) {
  std::vector<absl::string_view> lines = absl::StrSplit(message, '\n');
  if (lines.size() < 3 || lines[1].empty()) return std::string(lines[0]);
  return absl::StrCat(lines[0], " near \"", absl::CEscape(lines[1]), "\"");
}

absl::StatusOr<std::string> ReadSceneFile(const std::string& path) {
  std::error_code ec;
  const std::filesystem::file_status status = std::filesystem::status(path, ec);
  if (status.type() == std::filesystem::file_type::not_found) {
    return absl::NotFoundError(absl::StrCat(path, ": scene file not found"));
  }
  if (status.type() == std::filesystem::file_type::directory) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": is a directory, not a scene file"));
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) return absl::InvalidArgumentError(absl::StrCat(path, ": cannot open the scene file"));
  std::ostringstream text;
  text << in.rdbuf();  // sets failbit on `text` for an empty file: the JSON parser says so
  if (in.bad()) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": cannot read the scene file"));
  }
  return std::move(text).str();
}

// Moves `from`'s lines to `to`, or logs them as warnings when `to` is null.
void PassOn(std::vector<std::string>* from, std::vector<std::string>* to) {
  for (std::string& w : *from) {
    if (to != nullptr) {
      to->push_back(std::move(w));
    } else {
      spdlog::warn("{}", w);
    }
  }
}

// Reads and parses the scene file and applies the overrides. Returns the JSON names of the
// overridden bake fields, for messages.
absl::StatusOr<std::set<std::string>> ParseWithOverrides(const std::string& path,
                                                         const pdsm::v1::BakeParams& overrides,
                                                         pdsm::v1::Scene* message,
                                                         std::vector<std::string>* warnings) {
  if (IsWorldFile(path)) {
    std::vector<std::string> world_warnings;
    absl::StatusOr<pdsm::v1::Scene> world = ReadWorldFile(path, &world_warnings);
    if (!world.ok()) return world.status();
    *message = *std::move(world);
    PassOn(&world_warnings, warnings);
    return ApplyOverrides(overrides, message);
  }
  absl::StatusOr<std::string> text = ReadSceneFile(path);
  if (!text.ok()) return text.status();

  google::protobuf::util::JsonParseOptions options;
  options.ignore_unknown_fields = false;  // a misspelt field must not be silently dropped
  const auto parsed = google::protobuf::util::JsonStringToMessage(*text, message, options);
  if (!parsed.ok()) {
    // The parser names no field for a number beyond double's range (1e400): find it.
    if (const std::optional<OutOfRangeNumber> bad = FindOutOfRangeNumber(*text)) {
      return absl::InvalidArgumentError(absl::StrCat(path, ": ", bad->field,
                                                     ": must be finite (got ", bad->literal,
                                                     ", beyond the range of a double)"));
    }
    return absl::InvalidArgumentError(absl::StrCat(
        path, ": invalid scene JSON: ", OneLineJsonError(std::string(parsed.message()))));
  }
  std::vector<std::string> file_warnings;
  if (absl::Status s = internal::AddLightsFromMeshFiles(path, message, &file_warnings); !s.ok()) {
    return s;
  }
  PassOn(&file_warnings, warnings);
  return ApplyOverrides(overrides, message);
}

}  // namespace

absl::StatusOr<pdsm::v1::Scene> ParseSceneFile(const std::string& path,
                                               const pdsm::v1::BakeParams& overrides,
                                               std::vector<std::string>* warnings) {
  pdsm::v1::Scene message;
  absl::StatusOr<std::set<std::string>> overridden =
      ParseWithOverrides(path, overrides, &message, warnings);
  if (!overridden.ok()) return overridden.status();
  return message;
}

absl::StatusOr<pdsm::v1::BakeParams> EffectiveBakeParams(const pdsm::v1::BakeParams& bake, bool sun,
                                                         const std::string& label) {
  absl::StatusOr<BakeSettings> settings = internal::BuildBake(
      internal::FieldChecker(label, {}), bake, sun ? LightShape::kSun : LightShape::kRect);
  if (!settings.ok()) return settings.status();
  return internal::BakeParamsOf(*settings);
}

absl::StatusOr<pdsm::v1::BakeParams> EffectiveBakeParams(const pdsm::v1::Scene& scene,
                                                         const std::string& label, int light) {
  const pdsm::v1::Light& l = scene.lights_size() > 0 ? scene.lights(light) : scene.light();
  return EffectiveBakeParams(internal::MergedBakeParams(scene.bake(), l.bake()), l.has_sun(),
                             label);
}

std::string ResolveMeshPath(const std::string& scene_path, const std::string& mesh_path) {
  return ResolveAgainst(SceneFolder(scene_path), mesh_path);
}

absl::StatusOr<Scene> LoadSceneFile(const std::string& path, const pdsm::v1::BakeParams& overrides,
                                    std::vector<std::string>* warnings) {
  pdsm::v1::Scene message;
  absl::StatusOr<std::set<std::string>> overridden =
      ParseWithOverrides(path, overrides, &message, warnings);
  if (!overridden.ok()) return overridden.status();
  // No asset resolver: a scene file names meshes by path or inline, never by asset.
  return SceneBuilder(path, SceneFolder(path), *std::move(overridden), nullptr, warnings)
      .Build(message);
}

absl::StatusOr<Scene> SceneFromProto(const pdsm::v1::Scene& message,
                                     const std::string& source_label, const std::string& base_dir,
                                     const MeshAssetResolver& assets) {
  return SceneBuilder(source_label, base_dir, {}, &assets).Build(message);
}

}  // namespace pdsm
