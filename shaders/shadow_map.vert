#version 330 core
// Parallel shadow map of one light sample (DESIGN.md "Geometry of the bake"). The matrix maps
// light space to clip space so that NDC x, y span the rendered window of the shadow-map
// lattice exactly, and clip z / w is the reversed depth (n / z perspective, (far - z) /
// (far - near) orthographic); only its clipping matters, the depth test uses gl_FragDepth.
// GLSL 330 so the same source runs in the 3.3 fallback context. Compiled twice: as is for
// opaque casters, and with PDSM_ALPHA_TEST defined for alpha-tested ones (their UVs pass on).

layout(location = 0) in vec3 position_light;  // relative to the light centre
#ifdef PDSM_ALPHA_TEST
layout(location = 1) in vec2 uv;  // core/scene/alpha_mask.h: (0, 0) the image's top-left
out vec2 mask_uv;
#endif

uniform mat4 clip_from_light;

out float z_light;  // interpolated perspective-correctly: it is affine in light space

void main() {
  z_light = position_light.z;
#ifdef PDSM_ALPHA_TEST
  mask_uv = uv;
#endif
  gl_Position = clip_from_light * vec4(position_light, 1.0);
}
