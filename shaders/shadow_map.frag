#version 330 core
// Stores the biased light-space depth of the nearest caster (R32F colour), and writes the
// matching reversed depth so that the depth test (GL_GREATER, cleared to 0) keeps the nearest
// *biased* surface.

in float z_light;

uniform float depth_bias;       // light-space units
uniform float slope_bias;       // multiples of the depth change across one texel
uniform float footprint_scale;  // scales that per-texel depth change (e.g. to a PDSM pixel)
uniform int orthographic;       // 1 for the sun's sheared orthographic projection
uniform float z_clip_near;
uniform float z_clip_far;       // orthographic only

layout(location = 0) out float biased_depth;

#include "common/shadow_bias.glsl"  // BiasedDepth

// Reversed depth in [0, 1]: larger is nearer, 0 (the clear value) is beyond everything.
float ReversedDepth(float z) {
  if (orthographic != 0) return (z_clip_far - z) / (z_clip_far - z_clip_near);
  return z_clip_near / z;
}

void main() {
  float z_biased = BiasedDepth(z_light, depth_bias, slope_bias, footprint_scale);
  biased_depth = z_biased;
  gl_FragDepth = ReversedDepth(z_biased);
}
