// requires:
#ifndef PENUMBRA_LIB_POST_NOISE
#define PENUMBRA_LIB_POST_NOISE

/* Film grain as a point layer; see noise.py (grain_reference is the numpy twin of
 * noise_grain()). point[o]: amount, then as int bits grain size, frame, seed;
 * point[o + 1].x: monochrome (int bits). */

/* PCG output permutation of one LCG step: a well-mixed 32-bit hash of a 32-bit value. */
uint noise_pcg(uint v)
{
  uint state = v * 747796405u + 2891336453u;
  uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
  return (word >> 22u) ^ word;
}

/* Uniform in (-1, 1), symmetric about 0; every step is exact in float32. */
float noise_grain(uvec2 cell, uint channel, int frame, int seed)
{
  uint h = noise_pcg(uint(frame) + noise_pcg(uint(seed) * 4u + channel));
  h = noise_pcg(cell.x + noise_pcg(cell.y + h));
  int k = int(h >> 8u) - 8388608;
  return (float(k) + 0.5) / 8388608.0;
}

vec4 noise_point(vec4 c, int o)
{
  float amount = point[o].v.x;
  int grain_size = floatBitsToInt(point[o].v.y);
  int frame = floatBitsToInt(point[o].v.z);
  int seed = floatBitsToInt(point[o].v.w);
  bool monochrome = floatBitsToInt(point[o + 1].v.x) != 0;
  uvec2 cell = uvec2(ivec2(gl_FragCoord.xy) / grain_size);
  vec3 g;
  if (monochrome) {
    g = vec3(noise_grain(cell, 0u, frame, seed));
  }
  else {
    g = vec3(noise_grain(cell, 0u, frame, seed), noise_grain(cell, 1u, frame, seed), noise_grain(cell, 2u, frame, seed));
  }
  /* No stronger than the channel itself: light never goes negative, the mean stays. */
  return vec4(c.rgb + min(vec3(amount), max(c.rgb, vec3(0.0))) * g, c.a);
}

#endif /* PENUMBRA_LIB_POST_NOISE */
