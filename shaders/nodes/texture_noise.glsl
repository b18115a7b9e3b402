// requires: nodes/common.glsl nodes/texture_hash.glsl
#ifndef PENUMBRA_LIB_NODES_TEXTURE_NOISE
#define PENUMBRA_LIB_NODES_TEXTURE_NOISE

/* Blender's Noise Texture node: gradient noise in 1 to 4 dimensions and its fractal sums.
 *
 * - Gradient noise after Ken Perlin, "Improving Noise", SIGGRAPH 2002: the quintic fade
 *   6t^5 - 15t^4 + 10t^3 and gradients picked by the low bits of a lattice hash (lookup3,
 *   texture_hash.glsl), with the gradient sets, interpolation order and per-dimension range
 *   scales (0.25, 0.6616, 0.982, 0.8344) of Blender's noise (its perlin_1d .. perlin_4d and
 *   snoise_1d .. snoise_4d, adapted there from Open Shading Language).
 * - Like Blender, each coordinate is first reduced modulo 100000 (C fmod, exact) and shifted by
 *   0.5 when its magnitude is at least 1e6, so large coordinates keep their precision.
 * - Fractal sums as Blender defines them (after F. K. Musgrave, "Texturing and Modeling: A
 *   Procedural Approach", ch. 16): fBM (with Normalize), Multifractal, Hybrid Multifractal,
 *   Ridged Multifractal and Heterogeneous Terrain, with fractional Detail blending the last
 *   octave.
 * - The node: Distortion offsets the coordinate by noise at seeded offsets; Color is the value
 *   and two more evaluations at seeded offsets, as Blender's noise_texture_1d .. _4d.
 *
 * Deviation, on purpose: a non-finite coordinate (NaN, +-inf, or overflow from Scale or
 * Lacunarity) reads as signed noise 0 where Blender would return NaN. */

/* Noise Texture node `noise_type`. */
#define NOISE_FBM 0
#define NOISE_MULTIFRACTAL 1
#define NOISE_HYBRID_MULTIFRACTAL 2
#define NOISE_RIDGED_MULTIFRACTAL 3
#define NOISE_HETERO_TERRAIN 4

/* C's fmod(a, b) for finite a and b > 0, exactly: subtract b * 2^k, largest k first; each
 * subtraction is exact (Sterbenz), so the remainder is the exact one, as fmodf returns. */
float texture_fmod(float a, float b)
{
  float r = abs(a);
  int eb;
  frexp(b, eb);
  for (int i = 0; i < 160 && r >= b; i++) {
    int er;
    frexp(r, er);
    float d = ldexp(b, er - eb);
    if (d > r) {
      d = ldexp(b, er - eb - 1);
    }
    r -= d;
  }
  return (a < 0.0) ? -r : r;
}

/* The coordinate reduction of Blender's snoise: period 100000, and a half-cell shift for
 * |x| >= 1e6. */
float noise_wrap(float x)
{
  return texture_fmod(x, 100000.0) + ((abs(x) >= 1000000.0) ? 0.5 : 0.0);
}

float noise_fade(float t)
{
  return t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
}

float noise_negate_if(float v, uint condition)
{
  return (condition != 0u) ? -v : v;
}

float noise_grad(uint hash, float x)
{
  uint h = hash & 15u;
  float g = float(1u + (h & 7u));
  return noise_negate_if(g, h & 8u) * x;
}

float noise_grad(uint hash, float x, float y)
{
  uint h = hash & 7u;
  float u = (h < 4u) ? x : y;
  float v = 2.0 * ((h < 4u) ? y : x);
  return noise_negate_if(u, h & 1u) + noise_negate_if(v, h & 2u);
}

float noise_grad(uint hash, float x, float y, float z)
{
  uint h = hash & 15u;
  float u = (h < 8u) ? x : y;
  float vt = ((h == 12u) || (h == 14u)) ? x : z;
  float v = (h < 4u) ? y : vt;
  return noise_negate_if(u, h & 1u) + noise_negate_if(v, h & 2u);
}

float noise_grad(uint hash, float x, float y, float z, float w)
{
  uint h = hash & 31u;
  float u = (h < 24u) ? x : y;
  float v = (h < 16u) ? y : z;
  float s = (h < 8u) ? z : w;
  return noise_negate_if(u, h & 1u) + noise_negate_if(v, h & 2u) + noise_negate_if(s, h & 4u);
}

float noise_lerp2(float v0, float v1, float v2, float v3, float x, float y)
{
  float x1 = 1.0 - x;
  return (1.0 - y) * (v0 * x1 + v1 * x) + y * (v2 * x1 + v3 * x);
}

float noise_lerp3(float v0, float v1, float v2, float v3, float v4, float v5, float v6, float v7, vec3 f)
{
  float x1 = 1.0 - f.x;
  float y1 = 1.0 - f.y;
  float z1 = 1.0 - f.z;
  return z1 * (y1 * (v0 * x1 + v1 * f.x) + f.y * (v2 * x1 + v3 * f.x)) +
         f.z * (y1 * (v4 * x1 + v5 * f.x) + f.y * (v6 * x1 + v7 * f.x));
}

/* Unscaled gradient noise on wrapped coordinates (|x| < 100001: the int conversion is exact). */
float perlin_noise(float x)
{
  float xf = floor(x);
  int X = int(xf);
  float fx = x - xf;
  float u = noise_fade(fx);
  return mix(noise_grad(hash_int(X), fx), noise_grad(hash_int(X + 1), fx - 1.0), u);
}

float perlin_noise(vec2 p)
{
  vec2 pf = floor(p);
  ivec2 P = ivec2(pf);
  vec2 f = p - pf;
  return noise_lerp2(noise_grad(hash_int2(P.x, P.y), f.x, f.y),
                     noise_grad(hash_int2(P.x + 1, P.y), f.x - 1.0, f.y),
                     noise_grad(hash_int2(P.x, P.y + 1), f.x, f.y - 1.0),
                     noise_grad(hash_int2(P.x + 1, P.y + 1), f.x - 1.0, f.y - 1.0),
                     noise_fade(f.x),
                     noise_fade(f.y));
}

/* The 8 corner gradients of the cell at P (corner c: offset bits x = 1, y = 2, z = 4) for a
 * fixed 4th lattice coordinate handled by the caller. */
float perlin_cell3(ivec3 P, vec3 f)
{
  vec3 g = f - 1.0;
  return noise_lerp3(noise_grad(hash_int3(P.x, P.y, P.z), f.x, f.y, f.z),
                     noise_grad(hash_int3(P.x + 1, P.y, P.z), g.x, f.y, f.z),
                     noise_grad(hash_int3(P.x, P.y + 1, P.z), f.x, g.y, f.z),
                     noise_grad(hash_int3(P.x + 1, P.y + 1, P.z), g.x, g.y, f.z),
                     noise_grad(hash_int3(P.x, P.y, P.z + 1), f.x, f.y, g.z),
                     noise_grad(hash_int3(P.x + 1, P.y, P.z + 1), g.x, f.y, g.z),
                     noise_grad(hash_int3(P.x, P.y + 1, P.z + 1), f.x, g.y, g.z),
                     noise_grad(hash_int3(P.x + 1, P.y + 1, P.z + 1), g.x, g.y, g.z),
                     vec3(noise_fade(f.x), noise_fade(f.y), noise_fade(f.z)));
}

float perlin_noise(vec3 p)
{
  vec3 pf = floor(p);
  return perlin_cell3(ivec3(pf), p - pf);
}

float perlin_cell4(ivec4 P, vec4 f, int dw, float fw)
{
  int W = P.w + dw;
  vec3 g = f.xyz - 1.0;
  return noise_lerp3(noise_grad(hash_int4(P.x, P.y, P.z, W), f.x, f.y, f.z, fw),
                     noise_grad(hash_int4(P.x + 1, P.y, P.z, W), g.x, f.y, f.z, fw),
                     noise_grad(hash_int4(P.x, P.y + 1, P.z, W), f.x, g.y, f.z, fw),
                     noise_grad(hash_int4(P.x + 1, P.y + 1, P.z, W), g.x, g.y, f.z, fw),
                     noise_grad(hash_int4(P.x, P.y, P.z + 1, W), f.x, f.y, g.z, fw),
                     noise_grad(hash_int4(P.x + 1, P.y, P.z + 1, W), g.x, f.y, g.z, fw),
                     noise_grad(hash_int4(P.x, P.y + 1, P.z + 1, W), f.x, g.y, g.z, fw),
                     noise_grad(hash_int4(P.x + 1, P.y + 1, P.z + 1, W), g.x, g.y, g.z, fw),
                     vec3(noise_fade(f.x), noise_fade(f.y), noise_fade(f.z)));
}

float perlin_noise(vec4 p)
{
  vec4 pf = floor(p);
  ivec4 P = ivec4(pf);
  vec4 f = p - pf;
  return mix(perlin_cell4(P, f, 0, f.w), perlin_cell4(P, f, 1, f.w - 1.0), noise_fade(f.w));
}

/* Signed noise in about [-1, 1] (Blender's snoise), and unsigned in [0, 1]. */
float noise_snoise(float p)
{
  if (!texture_is_finite(p)) {
    return 0.0;
  }
  return 0.25 * perlin_noise(noise_wrap(p));
}

float noise_snoise(vec2 p)
{
  if (!(texture_is_finite(p.x) && texture_is_finite(p.y))) {
    return 0.0;
  }
  return 0.6616 * perlin_noise(vec2(noise_wrap(p.x), noise_wrap(p.y)));
}

float noise_snoise(vec3 p)
{
  if (!(texture_is_finite(p.x) && texture_is_finite(p.y) && texture_is_finite(p.z))) {
    return 0.0;
  }
  return 0.9820 * perlin_noise(vec3(noise_wrap(p.x), noise_wrap(p.y), noise_wrap(p.z)));
}

float noise_snoise(vec4 p)
{
  if (!(texture_is_finite(p.x) && texture_is_finite(p.y) && texture_is_finite(p.z) && texture_is_finite(p.w))) {
    return 0.0;
  }
  return 0.8344 * perlin_noise(vec4(noise_wrap(p.x), noise_wrap(p.y), noise_wrap(p.z), noise_wrap(p.w)));
}

#define NOISE_UNSIGNED(T) \
  float noise_unoise(T p) \
  { \
    return 0.5 * noise_snoise(p) + 0.5; \
  }
NOISE_UNSIGNED(float)
NOISE_UNSIGNED(vec2)
NOISE_UNSIGNED(vec3)
NOISE_UNSIGNED(vec4)

/* The fractal sums, one definition for every dimension. Detail is clamped to [0, 15] by the
 * node; octaves 0 .. int(detail), then the fractional part blends one more. */
#define NOISE_FRACTALS(T) \
  float noise_fbm(T p, float detail, float roughness, float lacunarity, bool normalize) \
  { \
    float fscale = 1.0; \
    float amp = 1.0; \
    float maxamp = 0.0; \
    float sum = 0.0; \
    for (int i = 0; i <= NODE_MAX_OCTAVE && i <= int(detail); i++) { \
      float t = noise_snoise(fscale * p); \
      sum += t * amp; \
      maxamp += amp; \
      amp *= roughness; \
      fscale *= lacunarity; \
    } \
    float rmd = detail - floor(detail); \
    if (rmd != 0.0) { \
      float t = noise_snoise(fscale * p); \
      float sum2 = sum + t * amp; \
      return normalize ? mix(0.5 * sum / maxamp + 0.5, 0.5 * sum2 / (maxamp + amp) + 0.5, rmd) : \
                         mix(sum, sum2, rmd); \
    } \
    return normalize ? 0.5 * sum / maxamp + 0.5 : sum; \
  } \
  float noise_multi_fractal(T p, float detail, float roughness, float lacunarity) \
  { \
    float value = 1.0; \
    float pwr = 1.0; \
    for (int i = 0; i <= NODE_MAX_OCTAVE && i <= int(detail); i++) { \
      value *= (pwr * noise_snoise(p) + 1.0); \
      pwr *= roughness; \
      p *= lacunarity; \
    } \
    float rmd = detail - floor(detail); \
    if (rmd != 0.0) { \
      value *= (rmd * pwr * noise_snoise(p) + 1.0); \
    } \
    return value; \
  } \
  float noise_hetero_terrain(T p, float detail, float roughness, float lacunarity, float offset) \
  { \
    float pwr = roughness; \
    float value = offset + noise_snoise(p); \
    p *= lacunarity; \
    for (int i = 1; i <= NODE_MAX_OCTAVE && i <= int(detail); i++) { \
      float increment = (noise_snoise(p) + offset) * pwr * value; \
      value += increment; \
      pwr *= roughness; \
      p *= lacunarity; \
    } \
    float rmd = detail - floor(detail); \
    if (rmd != 0.0) { \
      float increment = (noise_snoise(p) + offset) * pwr * value; \
      value += rmd * increment; \
    } \
    return value; \
  } \
  float noise_hybrid_multi_fractal( \
      T p, float detail, float roughness, float lacunarity, float offset, float gain) \
  { \
    float pwr = 1.0; \
    float value = 0.0; \
    float weight = 1.0; \
    for (int i = 0; i <= NODE_MAX_OCTAVE && (weight > 0.001) && (i <= int(detail)); i++) { \
      weight = min(weight, 1.0); \
      float signal = (noise_snoise(p) + offset) * pwr; \
      pwr *= roughness; \
      value += weight * signal; \
      weight *= gain * signal; \
      p *= lacunarity; \
    } \
    float rmd = detail - floor(detail); \
    if ((rmd != 0.0) && (weight > 0.001)) { \
      weight = min(weight, 1.0); \
      float signal = (noise_snoise(p) + offset) * pwr; \
      value += rmd * weight * signal; \
    } \
    return value; \
  } \
  float noise_ridged_multi_fractal( \
      T p, float detail, float roughness, float lacunarity, float offset, float gain) \
  { \
    float pwr = roughness; \
    float signal = offset - abs(noise_snoise(p)); \
    signal *= signal; \
    float value = signal; \
    float weight = 1.0; \
    for (int i = 1; i <= NODE_MAX_OCTAVE && i <= int(detail); i++) { \
      p *= lacunarity; \
      weight = clamp(signal * gain, 0.0, 1.0); \
      signal = offset - abs(noise_snoise(p)); \
      signal *= signal; \
      signal *= weight; \
      value += signal * pwr; \
      pwr *= roughness; \
    } \
    return value; \
  } \
  float noise_select(T p, \
                     float detail, \
                     float roughness, \
                     float lacunarity, \
                     float offset, \
                     float gain, \
                     int type, \
                     bool normalize) \
  { \
    if (type == NOISE_MULTIFRACTAL) { \
      return noise_multi_fractal(p, detail, roughness, lacunarity); \
    } \
    if (type == NOISE_HYBRID_MULTIFRACTAL) { \
      return noise_hybrid_multi_fractal(p, detail, roughness, lacunarity, offset, gain); \
    } \
    if (type == NOISE_RIDGED_MULTIFRACTAL) { \
      return noise_ridged_multi_fractal(p, detail, roughness, lacunarity, offset, gain); \
    } \
    if (type == NOISE_HETERO_TERRAIN) { \
      return noise_hetero_terrain(p, detail, roughness, lacunarity, offset); \
    } \
    return noise_fbm(p, detail, roughness, lacunarity, normalize); \
  }
NOISE_FRACTALS(float)
NOISE_FRACTALS(vec2)
NOISE_FRACTALS(vec3)
NOISE_FRACTALS(vec4)

/* Blender's seeded offsets in [100, 200]: 1D hashes the seed, 2D-4D hash (seed, axis). The
 * first argument only selects the dimension. */
float noise_offset(float like, float seed)
{
  return 100.0 + 100.0 * hash_float_to_float(seed);
}

float noise_seed_offset(float seed, float axis)
{
  return 100.0 + 100.0 * hash_vec2_to_float(vec2(seed, axis));
}

vec2 noise_offset(vec2 like, float seed)
{
  return vec2(noise_seed_offset(seed, 0.0), noise_seed_offset(seed, 1.0));
}

vec3 noise_offset(vec3 like, float seed)
{
  return vec3(noise_seed_offset(seed, 0.0), noise_seed_offset(seed, 1.0), noise_seed_offset(seed, 2.0));
}

vec4 noise_offset(vec4 like, float seed)
{
  return vec4(noise_seed_offset(seed, 0.0),
              noise_seed_offset(seed, 1.0),
              noise_seed_offset(seed, 2.0),
              noise_seed_offset(seed, 3.0));
}

float noise_distort(float p, float distortion)
{
  return p + noise_snoise(p + noise_offset(p, 0.0)) * distortion;
}

vec2 noise_distort(vec2 p, float distortion)
{
  return p + vec2(noise_snoise(p + noise_offset(p, 0.0)), noise_snoise(p + noise_offset(p, 1.0))) * distortion;
}

vec3 noise_distort(vec3 p, float distortion)
{
  return p + vec3(noise_snoise(p + noise_offset(p, 0.0)),
                  noise_snoise(p + noise_offset(p, 1.0)),
                  noise_snoise(p + noise_offset(p, 2.0))) *
                 distortion;
}

vec4 noise_distort(vec4 p, float distortion)
{
  /* A loop, not four calls in a row: four inlined 4-D noises take llvmpipe ~40 s to compile. */
  vec4 d = vec4(0.0);
  for (int i = 0; i < 4; i++) {
    d[i] = noise_snoise(p + noise_offset(p, float(i)));
  }
  return p + d * distortion;
}

/* The Noise Texture node for one dimension, on the already scaled coordinate p (1D: w; 2D:
 * vector.xy; 3D: vector; 4D: (vector, w)). Color in .rgb, Fac in .a (Fac equals Color's red);
 * the colour's green and blue use the seeds after the distortion's, as Blender's. */
#define NOISE_NODE(T, SEED) \
  vec4 node_tex_noise_at(T p, \
                         float detail, \
                         float roughness, \
                         float lacunarity, \
                         float offset, \
                         float gain, \
                         float distortion, \
                         int type, \
                         bool normalize) \
  { \
    detail = node_detail(detail); \
    roughness = max(roughness, 0.0); \
    if (distortion != 0.0) { \
      p = noise_distort(p, distortion); \
    } \
    float value = noise_select(p, detail, roughness, lacunarity, offset, gain, type, normalize); \
    float g = noise_select( \
        p + noise_offset(p, SEED), detail, roughness, lacunarity, offset, gain, type, normalize); \
    float b = noise_select( \
        p + noise_offset(p, SEED + 1.0), detail, roughness, lacunarity, offset, gain, type, normalize); \
    return vec4(value, g, b, value); \
  }
NOISE_NODE(float, 1.0)
NOISE_NODE(vec2, 2.0)
NOISE_NODE(vec3, 3.0)
NOISE_NODE(vec4, 4.0)

/* The node's inputs as Blender takes them: Vector, W and Scale (non-finite inputs read as 0).
 * Calls one dimension only; generated code that knows the dimension calls node_tex_noise_at. */
vec4 node_tex_noise(int dimensions,
                    vec3 vector,
                    float w,
                    float scale,
                    float detail,
                    float roughness,
                    float lacunarity,
                    float offset,
                    float gain,
                    float distortion,
                    int type,
                    bool normalize)
{
  vector = texture_finite(vector) * scale;
  w = texture_finite(w) * scale;
  if (dimensions == 1) {
    return node_tex_noise_at(w, detail, roughness, lacunarity, offset, gain, distortion, type, normalize);
  }
  if (dimensions == 2) {
    return node_tex_noise_at(vector.xy, detail, roughness, lacunarity, offset, gain, distortion, type, normalize);
  }
  if (dimensions == 3) {
    return node_tex_noise_at(vector, detail, roughness, lacunarity, offset, gain, distortion, type, normalize);
  }
  return node_tex_noise_at(vec4(vector, w), detail, roughness, lacunarity, offset, gain, distortion, type, normalize);
}

#endif /* PENUMBRA_LIB_NODES_TEXTURE_NOISE */
