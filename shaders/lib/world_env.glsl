// requires: lib/common.glsl
#ifndef PENUMBRA_LIB_WORLD_ENV
#define PENUMBRA_LIB_WORLD_ENV

/* The world's Environment Texture prefiltered for glossy lobes (engine/frame/world/prefilter.py):
 * the radiance a GGX lobe of roughness r reflects about a direction, as Karis' split sum takes
 * it (2013, "Real Shading in Unreal Engine 4": the lobe convolved with N = V = R, weighted by
 * the cosine), for the roughnesses of WORLD_ENV_LEVELS, each an equirectangular image in one
 * atlas texture, one level above the other. A level is (row of its first texel, width,
 * height, 0) in atlas texels; WORLD_ENV_LEVELS and its roughness step come from
 * prefilter.LEVELS. Directions map to the image as Blender maps them (Cycles'
 * direction_to_equirectangular): u = 0.5 - atan2(y, x) / 2pi, v = atan2(z, hypot(x, y)) / pi
 * + 0.5, in the image's frame. */

vec2 equirect_uv(vec3 d)
{
  return vec2(0.5 - atan(d.y, d.x) / (2.0 * M_PI), atan(d.z, length(d.xy)) / M_PI + 0.5);
}

vec3 equirect_direction(vec2 uv)
{
  float lon = (0.5 - uv.x) * 2.0 * M_PI;
  float lat = (uv.y - 0.5) * M_PI;
  return vec3(cos(lon) * cos(lat), sin(lon) * cos(lat), sin(lat));
}

/* Bilinear between texel centres of the equirectangular image at texels [row, row + h) x
 * [0, w) of ``tex`` (``level`` = (row, w, h)), wrapping in u and clamped in v: a lookup that
 * does not depend on the sampler's state nor read a neighbouring level. */
vec4 equirect_bilinear(sampler2D tex, ivec3 level, vec2 uv)
{
  vec2 st = uv * vec2(level.yz) - 0.5;
  if (!(abs(st.x) < 1e7 && abs(st.y) < 1e7)) {
    return vec4(0.0);
  }
  vec2 i = floor(st);
  vec2 f = st - i;
  int x0 = int(i.x) % level.y;
  x0 = (x0 < 0) ? x0 + level.y : x0;
  int x1 = (x0 + 1 == level.y) ? 0 : x0 + 1;
  int y0 = clamp(int(i.y), 0, level.z - 1) + level.x;
  int y1 = clamp(int(i.y) + 1, 0, level.z - 1) + level.x;
  vec4 a = texelFetch(tex, ivec2(x0, y0), 0);
  vec4 b = texelFetch(tex, ivec2(x1, y0), 0);
  vec4 c = texelFetch(tex, ivec2(x0, y1), 0);
  vec4 d = texelFetch(tex, ivec2(x1, y1), 0);
  return mix(mix(a, b, f.x), mix(c, d, f.x), f.y);
}

/* A GGX half vector about ``N`` for the uniform pair ``xi`` (Walter et al. 2007: the
 * distribution of normals D(h) (n.h) with alpha ``a``). */
vec3 ggx_half_vector(vec2 xi, float a, vec3 N)
{
  float phi = 2.0 * M_PI * xi.x;
  float cos_t = sqrt((1.0 - xi.y) / max(1.0 + (a * a - 1.0) * xi.y, 1e-12));
  float sin_t = sqrt(max(1.0 - cos_t * cos_t, 0.0));
  vec3 up = (abs(N.z) < 0.999) ? vec3(0.0, 0.0, 1.0) : vec3(1.0, 0.0, 0.0);
  vec3 tx = normalize(cross(up, N));
  vec3 ty = cross(N, tx);
  return normalize(tx * (sin_t * cos(phi)) + ty * (sin_t * sin(phi)) + N * cos_t);
}

/* The i-th of n points of the Hammersley set in [0, 1)^2. */
vec2 hammersley(int i, int n)
{
  uint b = uint(i);
  b = (b << 16u) | (b >> 16u);
  b = ((b & 0x55555555u) << 1u) | ((b & 0xAAAAAAAAu) >> 1u);
  b = ((b & 0x33333333u) << 2u) | ((b & 0xCCCCCCCCu) >> 2u);
  b = ((b & 0x0F0F0F0Fu) << 4u) | ((b & 0xF0F0F0F0u) >> 4u);
  b = ((b & 0x00FF00FFu) << 8u) | ((b & 0xFF00FF00u) >> 8u);
  return vec2((float(i) + 0.5) / float(n), float(b) * 2.3283064365386963e-10);
}

#endif /* PENUMBRA_LIB_WORLD_ENV */
