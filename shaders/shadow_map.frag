#version 330 core
// Stores the biased light-space depth of the nearest caster (R32F colour), and writes the
// matching reversed depth so that the depth test (GL_GREATER, cleared to 0) keeps the nearest
// *biased* surface. With PDSM_ALPHA_TEST defined (alpha-tested casters, core/scene/alpha_mask.h)
// a fragment whose mask is below the cutoff is discarded: light passes there.

in float z_light;

uniform float depth_bias;       // light-space units
uniform float slope_bias;       // multiples of the depth change across one texel
uniform float footprint_scale;  // scales that per-texel depth change (e.g. to a PDSM pixel)
uniform int orthographic;       // 1 for the sun's sheared orthographic projection
uniform float z_clip_near;
uniform float z_clip_far;       // orthographic only

#ifdef PDSM_ALPHA_TEST
in vec2 mask_uv;
uniform sampler2D alpha_mask;  // R8, GL_LINEAR, no mipmaps, the mask's wrap modes
uniform float alpha_cutoff;
#endif

layout(location = 0) out float biased_depth;

#include "common/shadow_bias.glsl"  // BiasedDepth

// Reversed depth in [0, 1]: larger is nearer, 0 (the clear value) is beyond everything.
float ReversedDepth(float z) {
  if (orthographic != 0) return (z_clip_far - z) / (z_clip_far - z_clip_near);
  return z_clip_near / z;
}

void main() {
  // Derivatives first: after a discard they are undefined in the discarded fragment's quad.
  float z_biased = BiasedDepth(z_light, depth_bias, slope_bias, footprint_scale);
#ifdef PDSM_ALPHA_TEST
  if (textureLod(alpha_mask, mask_uv, 0.0).r < alpha_cutoff) discard;
#endif
  biased_depth = z_biased;
  gl_FragDepth = ReversedDepth(z_biased);
}
