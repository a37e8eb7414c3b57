#version 430 core
// Shadow maps of the comparison modes (hard, pcf, pcss, vsm, multi-sm), rendered with the
// PDSM's orientation from a point of the light (parallel shadow maps, as in the bake).
// R: biased light-space depth of the nearest caster; G: its second moment for VSM, of the
// depth normalised to [z_near, z_far] so that float32 keeps the variance.
// The depth test runs on reversed depth (GL_GREATER, cleared to 0) written below.

in vec3 position_light;
in vec3 normal_light;

uniform float depth_bias;       // light-space units, the bake's (PDSM header)
uniform float slope_bias;       // multiples of the depth change across one texel
uniform float footprint_scale;  // 1 (FrameRenderer::EnsureShadowMaps says why)
uniform float z_near;           // the bake's depth range: VSM's normalisation
uniform float z_far;
uniform float clip_near;        // the shadow maps' clip range (ShadowClipRangeOf), wider than
uniform float clip_far;         // the bake's so that dynamic objects beyond it still cast
uniform int orthographic;

layout(location = 0) out vec2 depth_moments;

#include "common/shadow_bias.glsl"  // BiasedDepth: the bake's bias rule

void main() {
  float z = BiasedDepth(position_light.z, depth_bias, slope_bias, footprint_scale);
  float d = (z - z_near) / (z_far - z_near);
  depth_moments = vec2(z, d * d);
  gl_FragDepth = orthographic != 0 ? clamp((clip_far - z) / (clip_far - clip_near), 0.0, 1.0)
                                   : clamp(clip_near / z, 0.0, 1.0);
}
