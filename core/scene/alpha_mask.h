// Alpha-tested casters (issue #16 item 2; docs/scene_format.md, "Alpha-tested casters"): a
// triangle drawn with a mask casts a shadow only where the mask's texture, looked up at the
// point's UV, reaches the cutoff; elsewhere light passes, as through the holes of a foliage
// card. One definition serves the bake's shadow maps (the GL renderer samples the uploaded
// texture: shaders/shadow_map.frag) and the Embree reference (Sample below, the same filter in
// double): GL_LINEAR, no mipmaps, the mask's wrap modes.
//
// Frames: UV (0, 0) is the image's top-left corner, (1, 1) its bottom-right; texel (x, y) (row
// y from the top) covers u in [x, x + 1] / width, v in [y, y + 1] / height, its centre sampled
// exactly. That is glTF's convention; OBJ's V (up) is flipped to it on import.
#ifndef PDSM_CORE_SCENE_ALPHA_MASK_H_
#define PDSM_CORE_SCENE_ALPHA_MASK_H_

#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

namespace pdsm {

// Texels a side a mask may have: an 8192^2 mask is 64 MiB, uploaded once per shadow-map
// renderer (one per bake thread).
inline constexpr int kMaxAlphaMaskSide = 8192;

// How UVs outside [0, 1] wrap (glTF sampler wrapS / wrapT).
enum class TextureWrap : uint8_t { kRepeat = 0, kClampToEdge = 1, kMirroredRepeat = 2 };

// A mask: immutable once built; shared (std::shared_ptr<const AlphaMask>) by every copy of a
// scene and plan, and read from any thread.
struct AlphaMask {
  std::string label;  // for messages ("cards.gltf: material \"leaf\""); not part of the mask
  int width = 0, height = 0;   // each in [1, kMaxAlphaMaskSide]
  std::vector<uint8_t> alpha;  // width * height, row-major, row 0 at the top (v = 0); 255 = 1
  TextureWrap wrap_u = TextureWrap::kRepeat, wrap_v = TextureWrap::kRepeat;
  // A point casts where its filtered alpha (0..1) is >= cutoff; in (0, 1]. (glTF's
  // alphaCutoff divided by the material's base-colour alpha factor, which scales the texture's.)
  float cutoff = 0.5f;

  // The alpha at `uv`, bilinear between the four nearest texel centres, wrapped per axis.
  double Sample(const glm::dvec2& uv) const;
  bool CastsAt(const glm::dvec2& uv) const { return Sample(uv) >= cutoff; }
  // Whether the mask is well formed (sizes, alpha count, cutoff); what decoders check.
  bool Valid() const;
};

// Whether two masks cast the same shadow (everything but the label equal).
bool SameMask(const AlphaMask& a, const AlphaMask& b);

}  // namespace pdsm

#endif  // PDSM_CORE_SCENE_ALPHA_MASK_H_
