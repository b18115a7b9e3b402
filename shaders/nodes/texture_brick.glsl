// requires: nodes/texture_hash.glsl
#ifndef PENUMBRA_LIB_NODES_TEXTURE_BRICK
#define PENUMBRA_LIB_NODES_TEXTURE_BRICK

/* Blender's Brick Texture node: rows of Row Height, bricks of Brick Width, every Offset
 * Frequency-th row shifted by Offset times the brick width and every Squash Frequency-th row's
 * bricks Squash times as wide (both only when both frequencies are non-zero); mortar of Mortar
 * Size along the brick edges, blended by a smoothstep of Mortar Smooth.
 *
 * Each brick's tint mixes Color1 and Color2 by Blender's own integer noise of (row << 16) +
 * (brick & 0xffff) (a Lehmer-style polynomial hash on 31 bits), plus Bias, clamped to [0, 1].
 * Fac is the mortar amount; Color mixes the tinted brick colour with Mortar by it.
 *
 * Row and brick numbers convert to int as x86 does (INT_MIN out of range); a non-finite
 * coordinate, or one that overflows with Scale, reads as 0 where Blender would give NaN. */

/* Blender's brick noise of an integer, in [0, 1). */
float brick_noise(uint n)
{
  n = (n + 1013u) & 0x7fffffffu;
  n = (n >> 13u) ^ n;
  uint m = (n * (n * n * 60493u + 19990303u) + 1376312589u) & 0x7fffffffu;
  return 0.5 * (float(m) / 1073741824.0);
}

/* Whether row is a multiple of frequency (> 0), negative rows too. */
bool brick_row_is_multiple(int row, int frequency)
{
  uint magnitude = (row < 0) ? (0u - uint(row)) : uint(row);
  return (magnitude % uint(frequency)) == 0u;
}

/* Cycles' smoothstepf: 0 below 0, 1 above 1, (3 - 2t) t^2 between. */
float brick_smoothstep(float t)
{
  if (t <= 0.0) {
    return 0.0;
  }
  if (t >= 1.0) {
    return 1.0;
  }
  return (3.0 - 2.0 * t) * t * t;
}

/* (tint, mortar) of the already scaled point p. */
vec2 texture_brick(vec3 p,
                   float mortar_size,
                   float mortar_smooth,
                   float bias,
                   float brick_width,
                   float row_height,
                   float offset_amount,
                   int offset_frequency,
                   float squash_amount,
                   int squash_frequency)
{
  int row = texture_float_to_int(floor(p.y / row_height));
  float offset = 0.0;
  if (offset_frequency != 0 && squash_frequency != 0) {
    brick_width *= brick_row_is_multiple(row, squash_frequency) ? squash_amount : 1.0;
    offset = brick_row_is_multiple(row, offset_frequency) ? brick_width * offset_amount : 0.0;
  }
  int brick = texture_float_to_int(floor((p.x + offset) / brick_width));
  float x = (p.x + offset) - brick_width * float(brick);
  float y = p.y - row_height * float(row);
  float tint = clamp(brick_noise(uint((row << 16) + (brick & 0xffff))) + bias, 0.0, 1.0);
  float min_dist = min(min(x, y), min(brick_width - x, row_height - y));
  float mortar;
  if (min_dist >= mortar_size) {
    mortar = 0.0;
  }
  else if (mortar_smooth == 0.0) {
    mortar = 1.0;
  }
  else {
    mortar = brick_smoothstep((1.0 - min_dist / mortar_size) / mortar_smooth);
  }
  return vec2(tint, mortar);
}

/* The node (Offset and Squash Frequency are the node's `offset_frequency` and
 * `squash_frequency`): Color in .rgb, Fac in .a. */
vec4 node_tex_brick(vec3 vector,
                    vec3 color1,
                    vec3 color2,
                    vec3 mortar,
                    float scale,
                    float mortar_size,
                    float mortar_smooth,
                    float bias,
                    float brick_width,
                    float row_height,
                    float offset_amount,
                    int offset_frequency,
                    float squash_amount,
                    int squash_frequency)
{
  vec3 p = texture_finite(texture_finite(vector) * scale);
  vec2 tm = texture_brick(p,
                          mortar_size,
                          mortar_smooth,
                          bias,
                          brick_width,
                          row_height,
                          offset_amount,
                          offset_frequency,
                          squash_amount,
                          squash_frequency);
  float tint = tm.x;
  float f = tm.y;
  if (f != 1.0) {
    color1 = (1.0 - tint) * color1 + tint * color2;
  }
  return vec4(color1 * (1.0 - f) + mortar * f, f);
}

#endif /* PENUMBRA_LIB_NODES_TEXTURE_BRICK */
