// requires:
#ifndef PENUMBRA_LIB_WORLD_RATIO
#define PENUMBRA_LIB_WORLD_RATIO

/* The world's light as a ratio (Heitz, Hill and McGuire 2018): U x S per lobe, U the SH light
 * unshadowed, S = N / D the ratio of the world directions' sums of f cos V L / p (N) and
 * f cos L / p (D), accumulated with the same weights (lit.frag.glsl WORLD_RATIO). */

float world_luminance(vec3 c)
{
  return dot(c, vec3(0.2126, 0.7152, 0.0722));
}

/* S = n / d in [0, 1]; ``fallback`` where no direction reached the lobe (d = 0) or the sums
 * are not finite. */
float world_ratio_of(float n, float d, float fallback)
{
  float r = n / d;
  return (d > 0.0 && !isinf(d) && !isnan(r)) ? clamp(r, 0.0, 1.0) : fallback;
}

/* ``color`` (which carries the SH light U_d + U_s whole) with the world's light through its
 * ratios: color - U_d (1 - S_d) - U_s (1 - S_s), ``sums`` = (N_d, D_d, N_s, D_s). The specular
 * lobe falls back on the diffuse ratio, the diffuse on 1 (unshadowed). Nothing is taken below
 * zero: where the colour is not negative the result is not either, whatever the rounding. */
vec4 world_ratio_apply(vec4 color, vec3 u_d, vec3 u_s, vec4 sums)
{
  float S_d = world_ratio_of(sums.x, sums.y, 1.0);
  float S_s = world_ratio_of(sums.z, sums.w, S_d);
  vec3 taken = max(u_d, vec3(0.0)) * (1.0 - S_d) + max(u_s, vec3(0.0)) * (1.0 - S_s);
  return vec4(max(color.rgb - taken, min(color.rgb, vec3(0.0))), color.a);
}

#endif /* PENUMBRA_LIB_WORLD_RATIO */
