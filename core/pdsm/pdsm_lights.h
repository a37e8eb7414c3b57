// The lights of a PDSM file, as a consumer names them. A light is one part of the file, or the
// faces of a sphere light (core/scene/sphere_faces.h): parts named "SPHERE@FACE" whose headers
// carry face_tangent, stored one after the other. A point is answered by the face whose axis is
// nearest its direction from the sphere's centre: the face whose directions hold it.
#ifndef PDSM_CORE_PDSM_PDSM_LIGHTS_H_
#define PDSM_CORE_PDSM_PDSM_LIGHTS_H_

#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

#include "absl/status/statusor.h"
#include "core/pdsm/pdsm_image.h"

namespace pdsm {

struct PdsmLightParts {
  std::string name;        // "lamp"; "" for a one-light file's unnamed light
  std::vector<int> parts;  // file order; several only for a sphere's faces
};

// Every light of a file with these part headers (file order), in file order: one query column
// each.
std::vector<PdsmLightParts> LightsOfParts(std::span<const PdsmHeader> headers);

// The light named `name`: a light of LightsOfParts, or one part by its own name (one face of a
// sphere, "lamp@+x"). `name` empty: the file's only light. Errors name `path` and list the
// lights: FAILED_PRECONDITION for an empty name and several lights ("name one (--light
// NAME)"), NOT_FOUND for a name that is none of them.
absl::StatusOr<PdsmLightParts> FindLightParts(std::span<const PdsmHeader> headers,
                                              std::string_view path, std::string_view name);

// What a consumer's `--light NAME` selects: every light of the file when `name` is empty, else
// the one FindLightParts finds (with its errors, except that an empty name is never an error).
absl::StatusOr<std::vector<PdsmLightParts>> SelectLights(std::span<const PdsmHeader> headers,
                                                         std::string_view path,
                                                         std::string_view name);

// The part of `light` that answers at p_world: its only part, or the face whose axis (the
// part's frame.n) is nearest the point's direction from the centre (ties: the first in file
// order). REQUIRES: light.parts is not empty and indexes `headers`.
int PartAt(std::span<const PdsmHeader> headers, const PdsmLightParts& light,
           const glm::dvec3& p_world);

}  // namespace pdsm

#endif  // PDSM_CORE_PDSM_PDSM_LIGHTS_H_
