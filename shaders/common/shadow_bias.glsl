// The one depth-bias rule of every shadow map: the bake's (shaders/shadow_map.frag, the
// contract of ShadowMapCamera in worker/shadow_map_renderer.h) and the viewer's comparison
// modes (shaders/view/shadow_depth.frag). Included, not copied (cmake/pdsm_glsl.cmake).
// Fragment shaders only: it takes screen-space derivatives.
//
// The slope term is how much the caster's depth changes across one texel (|dz/dx| + |dz/dy|
// over screen pixels = shadow-map texels), so a tilted receiver that looks itself up a texel
// away from where it was rasterised still sits behind its own stored depth; footprint_scale
// widens that step when lookups can land farther (the bake: a PDSM pixel wider than a texel).
//   z, depth_bias: light-space units; slope_bias: multiples of that per-texel depth change.
float BiasedDepth(float z, float depth_bias, float slope_bias, float footprint_scale) {
  float depth_change_per_texel = abs(dFdx(z)) + abs(dFdy(z));
  return z + depth_bias + slope_bias * footprint_scale * depth_change_per_texel;
}
