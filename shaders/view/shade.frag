#version 430 core
// Shading of every viewer mode: the same lighting, only the attenuation A (fraction of the
// light hidden) differs. Direct light is scaled by (1 - A); the ambient term is not.
// Mode numbers match client/view/view_mode.h.

const int kModePdsm = 0;
const int kModeCpu = 1;
const int kModeHard = 2;
const int kModePcf = 3;
const int kModePcss = 4;
const int kModeVsm = 5;
const int kModeMultiSm = 6;
const int kModeShadowmask = 7;

in vec3 position_light;
in vec3 normal_light;
in vec2 texture_uv;

layout(location = 0) out vec4 colour;
layout(location = 1) out float attenuation_out;  // A; -1 outside the PDSM frustum, -3 pending,
                                                 // -4 not resident

uniform int mode;
uniform vec3 albedo;
uniform vec3 eye_light;
uniform int orthographic;   // the PDSM's (and every shadow map's) projection: 1 for the sun
uniform float ambient;

// ---- PDSM as a virtual texture (client/view/pdsm_tile_pool.h): a page table entry per tile,
// the resident tiles in up to 4 pool buffers (one binding holds at most
// GL_MAX_SHADER_STORAGE_BLOCK_SIZE). A tile's block: per pixel (offset from the block, count),
// then its vertices (z, A) as float bits -- the thesis' two levels (4.2.4), per tile.
// The parts shown: the light shaded (part 0, whose light space is the view's), or every light
// of the file, a sphere's faces one part each (client/view/frame_renderer.cc, PartsOf).
struct PdsmPart {
  mat4 light_from_view;  // this part's light space from the view's (identity for part 0)
  vec4 window;           // (s_min, t_min, pixels per window unit along s, along t)
  ivec4 size;            // (width, height, pixels per tile side, first page table entry)
  ivec4 info;            // (tiles a row, orthographic, first part past its light, sphere face)
  vec4 extra;            // (z_valid_min: nearer, the PDSM knows nothing; 0 none, -, -, -)
};
layout(std430, binding = 6) readonly buffer PdsmParts { PdsmPart pdsm_parts[]; };
layout(std430, binding = 7) readonly buffer PdsmPages { uint pdsm_pages[]; };  // (buffer << 28) | offset
layout(std430, binding = 0) readonly buffer PdsmPool0 { uvec2 pdsm_pool0[]; };
layout(std430, binding = 3) readonly buffer PdsmPool1 { uvec2 pdsm_pool1[]; };
layout(std430, binding = 4) readonly buffer PdsmPool2 { uvec2 pdsm_pool2[]; };
layout(std430, binding = 5) readonly buffer PdsmPool3 { uvec2 pdsm_pool3[]; };
uniform int pdsm_part_count;  // parts: 1 but in the every-light variant (PDSM_EVERY_LIGHT)
uniform int bilinear;         // 1: blend the 4 nearest pixels' results; 0: nearest pixel
const uint kTileNotResident = 0xFFFFFFFDu;  // over the GPU budget (--gpu-budget-mib)
const uint kTileEmpty = 0xFFFFFFFEu;        // no vertex: A = 0 everywhere in it
const uint kTilePending = 0xFFFFFFFFu;      // not baked yet (a job still running)
const float kPending = -3.0;
const float kNotResident = -4.0;

// ---- cpu mode: A per screen pixel, computed by the CPU.
uniform sampler2D cpu_attenuation;  // R32F, NaN outside the PDSM frustum

// ---- shadowmask mode: A from the texture `pdsm shadowmask` wrote over this receiver's UVs
// (bilinear, as an engine samples it); surfaces without one are shaded with the PDSM.
uniform int shadowmask_textured;  // 1 while drawing a receiver with its texture
uniform sampler2D shadowmask;     // R32F, row 0 at v = 0

// ---- shadow-map modes.
uniform sampler2D shadow_map;        // RG32F: biased z, normalised second moment
uniform sampler2DArray shadow_maps;  // R32F (in .r), one layer per light sample
layout(std430, binding = 1) readonly buffer LightSamples { vec2 light_samples[]; };
uniform int sample_count;
uniform vec2 sm_window_min;   // window (s, t) of the shadow maps
uniform vec2 sm_window_size;
uniform ivec2 sm_size;        // texels
uniform vec2 light_half_extent;  // light-space units (rect, disk); tan(half angle) (sun)
uniform float z_near;
uniform float z_far;
uniform int filter_radius;    // texels, pcf and vsm

// ---- pdsm and cpu modes: the dynamic objects' own soft shadow (they were not in the bake).
uniform int dynamic_count;           // maps (light samples); 0: no dynamic object casts
uniform sampler2DArray dynamic_maps;  // R32F (in .r), the dynamic objects alone, +inf: none
layout(std430, binding = 2) readonly buffer DynamicSamples { vec2 dynamic_samples[]; };
uniform vec2 dynamic_window_min;
uniform vec2 dynamic_window_size;
uniform ivec2 dynamic_sm_size;
uniform int dynamic_combine;  // 0: max(A_baked, A_dynamic); 1: 1 - (1 - A_baked)(1 - A_dynamic)
// Where the maps hold an object (window coordinates, over every sample, grown by a texel), and
// the samples' range: a fragment whose lookups all fall outside skips the maps.
uniform int dynamic_bounded;
uniform vec2 dynamic_reach_min;
uniform vec2 dynamic_reach_max;
uniform vec2 dynamic_sample_min;
uniform vec2 dynamic_sample_max;

uint PageOf(int part, ivec2 pixel) {
  ivec2 tile = pixel / pdsm_parts[part].size.z;
  return pdsm_pages[pdsm_parts[part].size.w + tile.y * pdsm_parts[part].info.x + tile.x];
}

// Word i of pool buffer b (buffer blocks are named one by one: an array of them could only be
// indexed uniformly across the draw).
uvec2 PoolWord(uint b, uint i) {
  if (b == 0u) return pdsm_pool0[i];
  if (b == 1u) return pdsm_pool1[i];
  if (b == 2u) return pdsm_pool2[i];
  return pdsm_pool3[i];
}

// One PDSM pixel's samples in the pool: buffer, first word, count (count 0 in an empty tile).
struct PixelSpan {
  uint b, offset, count;
};

PixelSpan SpanOf(int part, ivec2 pixel) {
  int tile_size = pdsm_parts[part].size.z;
  ivec2 tile = pixel / tile_size;
  uint page = PageOf(part, pixel);
  if (page >= kTileNotResident) return PixelSpan(0u, 0u, 0u);  // empty (callers turned the others away)
  uint b = page >> 28, block = page & 0x0FFFFFFFu;
  ivec2 local = pixel - tile * tile_size;
  int tile_width = min(tile_size, pdsm_parts[part].size.x - tile.x * tile_size);
  uvec2 entry = PoolWord(b, block + uint(local.y * tile_width + local.x));
  return PixelSpan(b, block + entry.x, entry.y);
}

// A(z) of one function: the last vertex with depth <= z and the next one, by binary search;
// linear between them, 0 before the first, the last value after the last (right-continuous at
// jumps) -- EvaluateAttenuation in core/pdsm/attenuation_function.cc.
float EvaluateSpan(PixelSpan s, float z) {
  uint b = s.b, offset = s.offset, count = s.count;
  if (count == 0u || z < uintBitsToFloat(PoolWord(b, offset).x)) return 0.0;
  uint lo = 1u, hi = count;  // first index in [lo, hi) with depth > z; index 0 is <= z
  while (lo < hi) {
    uint mid = (lo + hi) >> 1;
    if (uintBitsToFloat(PoolWord(b, offset + mid).x) <= z) lo = mid + 1u; else hi = mid;
  }
  vec2 a = uintBitsToFloat(PoolWord(b, offset + lo - 1u));
  // NaN (off a surfaces-only file's windows) is kept: clamp() of NaN is undefined in GLSL.
  if (lo == count) return isnan(a.y) ? a.y : clamp(a.y, 0.0, 1.0);
  vec2 c = uintBitsToFloat(PoolWord(b, offset + lo));
  float f = (z - a.x) / (c.x - a.x);
  float value = a.y + f * (c.y - a.y);
  return isnan(value) ? value : clamp(value, 0.0, 1.0);
}

// A refined pixel's refinement f (its first sample's attenuation is -f), 1 for a function --
// RefinementOf in core/pdsm/refined_pixel.h.
int RefinementOf(PixelSpan s) {
  if (s.count == 0u) return 1;
  float marker = uintBitsToFloat(PoolWord(s.b, s.offset).y);
  return marker <= -2.0 ? int(-marker) : 1;
}

// The band count of a refined pixel (its sample 1's depth); its bands follow, then its ends.
uint BandCount(PixelSpan s) { return uint(uintBitsToFloat(PoolWord(s.b, s.offset + 1u).x)); }

// Function m of a refined pixel of refinement f (0: the pixel's own, 1 + k: sub-function k):
// its end is the m-th of the f * f + 1 ends after the bands, its vertices follow them --
// RefinedFunction in core/pdsm/refined_pixel.cc.
PixelSpan RefinedSpan(PixelSpan s, int f, uint m) {
  uint ends = s.offset + 2u + 2u * BandCount(s);
  uint base = ends + 1u + uint(f * f);
  uint begin = m == 0u ? 0u : uint(uintBitsToFloat(PoolWord(s.b, ends + m - 1u).x));
  uint end = uint(uintBitsToFloat(PoolWord(s.b, ends + m).x));
  return PixelSpan(s.b, base + begin, end - begin);
}

// Whether the pixel is refined at depth z: refined, and z in one of its bands (RefinedAt).
bool RefinedAt(PixelSpan s, float z) {
  if (RefinementOf(s) == 1) return false;
  uint bands = BandCount(s);
  for (uint k = 0u; k < bands; ++k) {
    float lo = uintBitsToFloat(PoolWord(s.b, s.offset + 2u + 2u * k).x);
    float hi = uintBitsToFloat(PoolWord(s.b, s.offset + 3u + 2u * k).x);
    if (lo <= z && z <= hi) return true;
  }
  return false;
}

// The point of the lattice of refinement f at sub-pixel (i, j) of this pixel: its sub-pixel's
// A where it is refined at z and the sub-function is defined there, else its own function's;
// `sub` says which (LatticeAttenuation).
float LatticeAttenuation(PixelSpan s, int f, int i, int j, float z, out bool sub) {
  sub = false;
  int g = RefinementOf(s);
  if (g == 1) return EvaluateSpan(s, z);
  PixelSpan own = RefinedSpan(s, g, 0u);
  if (g > f || !RefinedAt(s, z)) return EvaluateSpan(own, z);
  PixelSpan ray = RefinedSpan(s, g, 1u + uint(i * g / f + g * (j * g / f)));
  if (ray.count != 0u) {
    float a = EvaluateSpan(ray, z);
    if (!isnan(a)) {
      sub = true;
      return a;
    }
  }
  return EvaluateSpan(own, z);
}

// A pixel's own function: the whole of an ordinary one, function 0 of a refined one.
float EvaluateOwn(PixelSpan s, float z) {
  int f = RefinementOf(s);
  return EvaluateSpan(f == 1 ? s : RefinedSpan(s, f, 0u), z);
}

// kPending or kNotResident when a page the lookup reads is so (pending first), else 0.
float MissingPage(uint page) {
  if (page == kTilePending) return kPending;
  return page == kTileNotResident ? kNotResident : 0.0;
}

vec2 WindowFromLight(vec3 p, vec2 sample_offset) {
  if (orthographic != 0) return p.xy - sample_offset * p.z;
  return (p.xy - sample_offset) / p.z;
}

// Thesis ch. 4: project `q` (part `part`'s light space), evaluate the 4 neighbours at z, blend
// the results (never depths). -1 outside the frustum (QueryAttenuation's NaN).
float PdsmAttenuationOf(int part, vec3 q) {
  bool ortho = pdsm_parts[part].info.y != 0;
  if (!ortho && !(q.z > 0.0)) return -1.0;
  if (q.z < pdsm_parts[part].extra.x) return -1.0;
  vec2 st = ortho ? q.xy : q.xy / q.z;
  vec2 pixel = (st - pdsm_parts[part].window.xy) * pdsm_parts[part].window.zw;
  ivec2 size = pdsm_parts[part].size.xy;
  if (any(lessThan(pixel, vec2(0.0))) || any(greaterThan(pixel, vec2(size)))) return -1.0;
  ivec2 last = size - 1;
  if (bilinear == 0) {
    ivec2 nearest = clamp(ivec2(floor(pixel)), ivec2(0), last);
    float missing = MissingPage(PageOf(part, nearest));
    if (missing != 0.0) return missing;
    PixelSpan held = SpanOf(part, nearest);
    int rf = RefinementOf(held);
    // A refined pixel: its nearest sub-pixel where it is refined.
    ivec2 sub = clamp(ivec2(floor((pixel - vec2(nearest)) * float(rf))), ivec2(0), ivec2(rf - 1));
    bool defined;
    float a = LatticeAttenuation(held, rf, sub.x, sub.y, q.z, defined);
    return isnan(a) ? -1.0 : a;
  }
  vec2 f = pixel - 0.5;
  vec2 base = floor(f);
  vec2 w = f - base;
  ivec2 p0 = clamp(ivec2(base), ivec2(0), last);
  ivec2 p1 = clamp(ivec2(base) + 1, ivec2(0), last);
  float m00 = MissingPage(PageOf(part, p0)), m11 = MissingPage(PageOf(part, p1));
  float m01 = MissingPage(PageOf(part, ivec2(p0.x, p1.y)));
  float m10 = MissingPage(PageOf(part, ivec2(p1.x, p0.y)));
  if (m00 == kPending || m11 == kPending || m01 == kPending || m10 == kPending) return kPending;
  if (min(min(m00, m11), min(m01, m10)) == kNotResident) return kNotResident;
  PixelSpan s00 = SpanOf(part, ivec2(p0.x, p0.y)), s10 = SpanOf(part, ivec2(p1.x, p0.y));
  PixelSpan s01 = SpanOf(part, ivec2(p0.x, p1.y)), s11 = SpanOf(part, ivec2(p1.x, p1.y));
  // Where one of the four is refined at this depth, the rays of the finest such lattice around
  // the point, each from the pixel holding it (BilinearAttenuationOf in core/pdsm/pdsm_query.h).
  int rf = 1;
  if (RefinedAt(s00, q.z)) rf = max(rf, RefinementOf(s00));
  if (RefinedAt(s10, q.z)) rf = max(rf, RefinementOf(s10));
  if (RefinedAt(s01, q.z)) rf = max(rf, RefinementOf(s01));
  if (RefinedAt(s11, q.z)) rf = max(rf, RefinementOf(s11));
  float a;
  bool defined = false;
  if (rf > 1) {
    vec2 u = pixel * float(rf) - 0.5;
    vec2 ub = floor(u);
    vec2 sw = u - ub;
    ivec2 last_ray = size * rf - 1;
    float v[4];
    for (int k = 0; k < 4; ++k) {
      ivec2 ray = clamp(ivec2(ub) + ivec2(k & 1, k >> 1), ivec2(0), last_ray);
      ivec2 in_pixel = ray / rf;
      PixelSpan source = in_pixel.y != p0.y ? (in_pixel.x != p0.x ? s11 : s01)
                                            : (in_pixel.x != p0.x ? s10 : s00);
      bool sub;
      v[k] = LatticeAttenuation(source, rf, ray.x - in_pixel.x * rf, ray.y - in_pixel.y * rf, q.z,
                                sub);
      defined = defined || sub;
    }
    a = (1.0 - sw.y) * ((1.0 - sw.x) * v[0] + sw.x * v[1]) + sw.y * ((1.0 - sw.x) * v[2] + sw.x * v[3]);
  }
  if (!defined) {
    float a00 = EvaluateOwn(s00, q.z), a10 = EvaluateOwn(s10, q.z);
    float a01 = EvaluateOwn(s01, q.z), a11 = EvaluateOwn(s11, q.z);
    a = (1.0 - w.y) * ((1.0 - w.x) * a00 + w.x * a10) + w.y * ((1.0 - w.x) * a01 + w.x * a11);
  }
  return isnan(a) ? -1.0 : a;  // a NaN neighbour: unknown, as QueryAttenuation says
}

// The light shaded (part 0, in the view's own light space).
float PdsmAttenuation(vec3 p) { return PdsmAttenuationOf(0, p); }

// Texel coordinates (continuous) of p in the shadow map of the sample at sample_offset.
vec2 ShadowMapTexel(vec3 p, vec2 sample_offset) {
  return (WindowFromLight(p, sample_offset) - sm_window_min) / sm_window_size * vec2(sm_size);
}

// 1 where the texel's caster is nearer than p (the bias is in the stored depth); outside the
// map, lit.
float ShadowTest(ivec2 texel, float z) {
  if (any(lessThan(texel, ivec2(0))) || any(greaterThanEqual(texel, sm_size))) return 0.0;
  return z > texelFetch(shadow_map, texel, 0).r ? 1.0 : 0.0;
}

float HardShadow(vec3 p) { return ShadowTest(ivec2(floor(ShadowMapTexel(p, vec2(0.0)))), p.z); }

float Pcf(vec3 p) {
  ivec2 centre = ivec2(floor(ShadowMapTexel(p, vec2(0.0))));
  float sum = 0.0;
  for (int y = -filter_radius; y <= filter_radius; ++y) {
    for (int x = -filter_radius; x <= filter_radius; ++x) sum += ShadowTest(centre + ivec2(x, y), p.z);
  }
  float side = float(2 * filter_radius + 1);
  return sum / (side * side);
}

// Vogel (golden-angle spiral) disk: evenly spread taps without a table, turned by `rotation`.
vec2 VogelDisk(int i, int n, float rotation) {
  float r = sqrt((float(i) + 0.5) / float(n));
  float theta = float(i) * 2.39996323 + rotation;
  return r * vec2(cos(theta), sin(theta));
}

// Interleaved gradient noise (Jimenez 2014): a per-pixel disk rotation turns the banding of
// a few fixed taps into fine, deterministic noise.
float PixelRotation() {
  return 6.2831853 * fract(52.9829189 * fract(dot(gl_FragCoord.xy, vec2(0.06711056, 0.00583715))));
}

// Window units covered by the light seen from depth z_receiver through depth z_between
// (perspective: w (1/z_between - 1/z_receiver); sun: tan (z_receiver - z_between)).
vec2 LightFootprint(float z_between, float z_receiver) {
  if (orthographic != 0) return light_half_extent * max(z_receiver - z_between, 0.0);
  return light_half_extent * max(1.0 / z_between - 1.0 / z_receiver, 0.0);
}

// PCSS (Fernando 2005) with the real light size: blocker search over the light's footprint
// from the nearest caster depth, penumbra from the average blocker depth, then PCF; both over
// a 32-tap disk rotated per pixel.
float Pcss(vec3 p) {
  const int kTaps = 32;
  const float kMaxRadiusTexels = 48.0;
  vec2 centre = ShadowMapTexel(p, vec2(0.0));
  float rotation = PixelRotation();
  vec2 texels_per_unit = vec2(sm_size) / sm_window_size;
  vec2 search = min(LightFootprint(z_near, p.z) * texels_per_unit, vec2(kMaxRadiusTexels));
  float blocker_sum = 0.0;
  int blockers = 0;
  for (int i = 0; i < kTaps; ++i) {
    ivec2 texel = ivec2(floor(centre + VogelDisk(i, kTaps, rotation) * search));
    if (any(lessThan(texel, ivec2(0))) || any(greaterThanEqual(texel, sm_size))) continue;
    float z_caster = texelFetch(shadow_map, texel, 0).r;
    if (z_caster < p.z) { blocker_sum += z_caster; ++blockers; }
  }
  if (blockers == 0) return 0.0;
  float z_blocker = blocker_sum / float(blockers);
  vec2 radius = max(min(LightFootprint(z_blocker, p.z) * texels_per_unit,
                        vec2(kMaxRadiusTexels)), vec2(0.5));
  float sum = 0.0;
  for (int i = 0; i < kTaps; ++i) {
    sum += ShadowTest(ivec2(floor(centre + VogelDisk(i, kTaps, rotation) * radius)), p.z);
  }
  return sum / float(kTaps);
}

// Variance shadow maps (Donnelly & Lauritzen 2006): box-filtered moments, Chebyshev's bound,
// with light-bleeding reduction (bound below 0.2 counts as shadow).
float Vsm(vec3 p) {
  ivec2 centre = ivec2(floor(ShadowMapTexel(p, vec2(0.0))));
  vec2 moments = vec2(0.0);
  float range = z_far - z_near;
  int n = 0;
  for (int y = -filter_radius; y <= filter_radius; ++y) {
    for (int x = -filter_radius; x <= filter_radius; ++x) {
      ivec2 texel = clamp(centre + ivec2(x, y), ivec2(0), sm_size - 1);
      vec2 m = texelFetch(shadow_map, texel, 0).rg;
      moments += vec2((m.r - z_near) / range, m.g);
      ++n;
    }
  }
  moments /= float(n);
  float d = (p.z - z_near) / range;
  if (d <= moments.x) return 0.0;
  float variance = max(moments.y - moments.x * moments.x, 1e-7);
  float delta = d - moments.x;
  float p_max = variance / (variance + delta * delta);
  return 1.0 - clamp((p_max - 0.2) / 0.8, 0.0, 1.0);
}

// The brute force a PDSM replaces: one shadow map per light sample, averaged.
float MultiShadowMap(vec3 p) {
  float hidden = 0.0;
  for (int k = 0; k < sample_count; ++k) {
    ivec2 texel = ivec2(floor(ShadowMapTexel(p, light_samples[k])));
    if (any(lessThan(texel, ivec2(0))) || any(greaterThanEqual(texel, sm_size))) continue;
    if (p.z > texelFetch(shadow_maps, ivec3(texel, k), 0).r) hidden += 1.0;
  }
  return hidden / float(max(sample_count, 1));
}

// The fraction of the dynamic objects' light samples they hide from p: the average of
// dynamic_count hard tests, one per map (the same parallel shadow maps as multi-sm's).
float DynamicAttenuation(vec3 p) {
  if (orthographic == 0 && !(p.z > 0.0)) return 0.0;
  if (dynamic_bounded != 0) {
    vec2 a = WindowFromLight(p, dynamic_sample_min), b = WindowFromLight(p, dynamic_sample_max);
    if (any(lessThan(max(a, b), dynamic_reach_min)) ||
        any(greaterThan(min(a, b), dynamic_reach_max))) {
      return 0.0;
    }
  }
  float hidden = 0.0;
  for (int k = 0; k < dynamic_count; ++k) {
    vec2 st = WindowFromLight(p, dynamic_samples[k]);
    ivec2 texel = ivec2(floor((st - dynamic_window_min) / dynamic_window_size *
                              vec2(dynamic_sm_size)));
    if (any(lessThan(texel, ivec2(0))) || any(greaterThanEqual(texel, dynamic_sm_size))) continue;
    if (p.z > texelFetch(dynamic_maps, ivec3(texel, k), 0).r) hidden += 1.0;
  }
  return hidden / float(dynamic_count);
}

// The baked attenuation (or -1 outside the PDSM, -3 pending) with the dynamic objects' shadow.
float WithDynamicShadow(float baked, vec3 p) {
  if (dynamic_count == 0 || baked == kPending || baked == kNotResident) return baked;
  float d = DynamicAttenuation(p);
  if (baked < 0.0) return d > 0.0 ? d : baked;  // outside the PDSM: only the dynamic shadow
  return dynamic_combine == 0 ? max(baked, d) : 1.0 - (1.0 - baked) * (1.0 - d);
}

float Attenuation(vec3 p) {
  if (mode == kModePdsm) return WithDynamicShadow(PdsmAttenuation(p), p);
  if (mode == kModeShadowmask) {
    float baked = shadowmask_textured != 0 ? texture(shadowmask, texture_uv).r : PdsmAttenuation(p);
    return WithDynamicShadow(baked, p);
  }
  if (mode == kModeCpu) {
    float a = texelFetch(cpu_attenuation, ivec2(gl_FragCoord.xy), 0).r;
    return WithDynamicShadow(isnan(a) ? -1.0 : a, p);
  }
  // Behind a perspective light the shadow maps have no projection (and float-to-int of the
  // inf/NaN it would give is undefined): such points are lit.
  if (orthographic == 0 && !(p.z > 0.0)) return 0.0;
  if (mode == kModeHard) return HardShadow(p);
  if (mode == kModePcf) return Pcf(p);
  if (mode == kModePcss) return Pcss(p);
  if (mode == kModeVsm) return Vsm(p);
  return MultiShadowMap(p);
}

#ifdef PDSM_EVERY_LIGHT  // the variant client/view/frame_renderer.cc builds for it
// Every light of the file (pdsm mode without --light): each light's direct term d_i, from its
// own centre as in the one-light case (a sphere's from its centre, without an emitter
// cosine), and its A_i; a sphere's A from the face whose axis is nearest the point's direction
// from its centre (PartAt in core/pdsm/pdsm_lights.h). `hidden` is the fraction of the direct
// light the lights hide, 1 - sum d_i (1 - A_i) / sum d_i (0 where none reaches), or kPending /
// kNotResident where a light's tiles are so. Returns the direct term shaded: min(sum d_i, 1)
// (1 - hidden), so that one light shades as in the one-light case and several do not wash
// each other's shadows out.
float EveryLight(vec3 p, vec3 n, out float hidden) {
  float arrives = 0.0, total = 0.0;
  bool pending = false, not_resident = false;
  for (int i = 0; i < pdsm_part_count; i = pdsm_parts[i].info.z) {
    int chosen = i;
    vec3 q = (pdsm_parts[i].light_from_view * vec4(p, 1.0)).xyz;
    float best = q.z / length(q);
    for (int f = i + 1; f < pdsm_parts[i].info.z; ++f) {
      vec3 qf = (pdsm_parts[f].light_from_view * vec4(p, 1.0)).xyz;
      float score = qf.z / length(qf);
      if (score > best) {
        best = score;
        chosen = f;
        q = qf;
      }
    }
    bool ortho = pdsm_parts[chosen].info.y != 0;
    vec3 m = mat3(pdsm_parts[chosen].light_from_view) * n;
    vec3 to_light = ortho ? vec3(0.0, 0.0, -1.0) : normalize(-q);
    bool planar = !ortho && pdsm_parts[chosen].info.w == 0;
    float direct = max(dot(m, to_light), 0.0) * (planar ? max(-to_light.z, 0.0) : 1.0);
    float a = PdsmAttenuationOf(chosen, q);
    pending = pending || a == kPending;
    not_resident = not_resident || a == kNotResident;
    arrives += direct * (1.0 - max(a, 0.0));  // outside its frustum: lit
    total += direct;
  }
  float fraction = total > 0.0 ? arrives / total : 1.0;
  hidden = pending ? kPending : not_resident ? kNotResident : 1.0 - fraction;
  return min(total, 1.0) * fraction;
}
#endif

void main() {
  vec3 p = position_light;
  vec3 n = normalize(normal_light);
  if (dot(n, eye_light - p) < 0.0) n = -n;  // two-sided: thin plates are seen from both sides
  float a;
  vec3 linear;
#ifdef PDSM_EVERY_LIGHT
  linear = albedo * (ambient + (1.0 - ambient) * EveryLight(p, n, a));
#else
  {
    // Direct light from the light centre: Lambert at the receiver, and the emitter's cosine
    // for a planar light (1 for the sun).
    vec3 to_light = orthographic != 0 ? vec3(0.0, 0.0, -1.0) : normalize(-p);
    float emitter_cos = orthographic != 0 ? 1.0 : max(-to_light.z, 0.0);
    float direct = max(dot(n, to_light), 0.0) * emitter_cos;
    a = Attenuation(p);
    float visible = 1.0 - max(a, 0.0);  // outside the frustum: no information, lit
    linear = albedo * (ambient + (1.0 - ambient) * direct * visible);
  }
#endif
  attenuation_out = a;
  // Not baked yet: lit, under a blue hatch that moves with the surface.
  if (a == kPending) {
    float hatch = step(0.5, fract((gl_FragCoord.x + gl_FragCoord.y) / 16.0));
    linear = mix(linear, vec3(0.25, 0.45, 0.9), 0.25 + 0.2 * hatch);
  }
  // Baked, but its tile did not fit the GPU budget: lit, under an amber hatch the other way.
  if (a == kNotResident) {
    float hatch = step(0.5, fract((gl_FragCoord.x - gl_FragCoord.y) / 16.0));
    linear = mix(linear, vec3(0.9, 0.6, 0.2), 0.25 + 0.2 * hatch);
  }
  colour = vec4(pow(clamp(linear, 0.0, 1.0), vec3(1.0 / 2.2)), 1.0);
}
