#include "server/job_lights.h"

#include <charconv>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"

namespace pdsm {

std::vector<JobLight> MakeJobLights(const std::string& job_id, std::vector<PlannedLight> plans) {
  std::vector<JobLight> lights;
  lights.reserve(plans.size());
  const int count = static_cast<int>(plans.size());
  int offset = 0;
  for (int i = 0; i < count; ++i) {
    JobLight light;
    light.index = i;
    light.name = plans[i].plan->header.light_name;
    light.fingerprint = std::move(plans[i].fingerprint);
    light.plan = std::move(plans[i].plan);
    light.tile_offset = offset;
    light.engine_id = EngineJobId(job_id, i, count);
    offset += light.tile_count();
    lights.push_back(std::move(light));
  }
  return lights;
}

std::string EngineJobId(const std::string& job_id, int light, int light_count) {
  if (light_count == 1) return job_id;
  return absl::StrFormat("%s/%05d", job_id, light);
}

namespace {
constexpr std::string_view kLevelSuffix = "/refined";
}  // namespace

std::string LevelEngineJobId(const std::string& light_engine_id) {
  return light_engine_id + std::string(kLevelSuffix);
}

std::optional<EngineJobOf> ParseEngineJobId(std::string_view engine_id) {
  const bool level = engine_id.ends_with(kLevelSuffix);
  if (level) engine_id.remove_suffix(kLevelSuffix.size());
  const size_t slash = engine_id.find('/');
  if (slash == std::string_view::npos) return EngineJobOf{std::string(engine_id), 0, level};
  const std::string_view digits = engine_id.substr(slash + 1);
  int light = -1;
  const auto [end, error] = std::from_chars(digits.data(), digits.data() + digits.size(), light);
  if (error != std::errc() || end != digits.data() + digits.size() || light < 0) {
    return std::nullopt;
  }
  return EngineJobOf{std::string(engine_id.substr(0, slash)), light, level};
}

absl::StatusOr<int> FindJobLight(const std::vector<JobLight>& lights, std::string_view name,
                                 const std::string& job_id) {
  if (name.empty() && lights.size() == 1) return 0;
  std::vector<std::string> names;
  for (const JobLight& light : lights) {
    if (!name.empty() && light.name == name) return light.index;
    names.push_back(light.name);
  }
  const std::string listed = absl::StrCat("\"", absl::StrJoin(names, "\", \""), "\"");
  if (name.empty()) {
    return absl::FailedPreconditionError(absl::StrFormat(
        "job %s has %d lights (%s): name one (light)", job_id, lights.size(), listed));
  }
  return absl::NotFoundError(
      absl::StrFormat("job %s has no light \"%s\"; its lights: %s", job_id, name, listed));
}

}  // namespace pdsm
