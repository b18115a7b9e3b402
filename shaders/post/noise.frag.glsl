/* Film grain; see noise.py (grain_reference is the numpy twin of grain()). */

/* PCG output permutation of one LCG step: a well-mixed 32-bit hash of a 32-bit value. */
uint pcg(uint v)
{
  uint state = v * 747796405u + 2891336453u;
  uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
  return (word >> 22u) ^ word;
}

/* Uniform in (-1, 1), symmetric about 0; every step is exact in float32. */
float grain(uvec2 cell, uint channel)
{
  uint h = pcg(uint(frame) + pcg(uint(seed) * 4u + channel));
  h = pcg(cell.x + pcg(cell.y + h));
  int k = int(h >> 8u) - 8388608;
  return (float(k) + 0.5) / 8388608.0;
}

void main()
{
  vec4 c = post_source();
  uvec2 cell = uvec2(ivec2(gl_FragCoord.xy) / grain_size);
  vec3 g;
  if (monochrome != 0) {
    g = vec3(grain(cell, 0u));
  }
  else {
    g = vec3(grain(cell, 0u), grain(cell, 1u), grain(cell, 2u));
  }
  out_color = post_mix(vec4(c.rgb + amount * g, c.a));
}
