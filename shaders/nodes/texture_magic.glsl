// requires: nodes/texture_hash.glsl nodes/texture_noise.glsl
#ifndef PENUMBRA_LIB_NODES_TEXTURE_MAGIC
#define PENUMBRA_LIB_NODES_TEXTURE_MAGIC

/* Blender's Magic Texture node: three waves of the point, sin(5 (x + y + z)), cos(5 (-x + y - z))
 * and -cos(5 (-x - y + z)), fed Depth times (0 to 10) through Blender's fixed chain of sines and
 * cosines of each other, each step scaled by Distortion; the colour is 0.5 minus the three
 * divided by 2 Distortion (when Distortion is not 0), Fac their average.
 *
 * Each coordinate is first wrapped into (-2pi, 2pi) by C's fmod (texture_fmod of
 * texture_noise.glsl, exact), as Blender does to keep sin and cos accurate far out. Where the
 * scale enters differs between Blender lines, and the patterns differ for any Scale that is not
 * a multiple of 2/5:
 * - MAGIC_WRAP_UNSCALED (Blender 4.5): fmod(coordinate, 2pi), then times 5 * Scale;
 * - MAGIC_WRAP_SCALED (Blender 5): fmod(coordinate * Scale, 2pi), then times 5.
 * (EEVEE, on both lines, wraps after Scale with a floored modulo: a shift by 2pi, which the
 * factor 5 turns into whole turns, so it draws Blender 5's pattern up to rounding.)
 *
 * Deviation, on purpose: a non-finite coordinate, or one that overflows with Scale, reads as 0
 * where Blender would return NaN. Depth is clamped to [0, 10] as Blender's property is. */

#define MAGIC_WRAP_UNSCALED 0
#define MAGIC_WRAP_SCALED 1

/* The node: Color in .rgb, Fac in .a. */
vec4 node_tex_magic(vec3 vector, float scale, float distortion, int depth, int wrap)
{
  vec3 p = texture_finite(vector);
  if (wrap == MAGIC_WRAP_SCALED) {
    p = texture_finite(p * scale);
  }
  p = vec3(texture_fmod(p.x, 6.2831853071795864),
           texture_fmod(p.y, 6.2831853071795864),
           texture_fmod(p.z, 6.2831853071795864));
  vec3 a = vec3(p.x + p.y + p.z, -p.x + p.y - p.z, -p.x - p.y + p.z) * 5.0;
  if (wrap == MAGIC_WRAP_UNSCALED) {
    a = texture_finite(a * scale);
  }
  float x = sin(a.x);
  float y = cos(a.y);
  float z = -cos(a.z);
  depth = clamp(depth, 0, 10);
  if (depth > 0) {
    x *= distortion;
    y *= distortion;
    z *= distortion;
    y = -cos(x - y + z) * distortion;
  }
  if (depth > 1) {
    x = cos(x - y - z) * distortion;
  }
  if (depth > 2) {
    z = sin(-x - y - z) * distortion;
  }
  if (depth > 3) {
    x = -cos(-x + y - z) * distortion;
  }
  if (depth > 4) {
    y = -sin(-x + y + z) * distortion;
  }
  if (depth > 5) {
    y = -cos(-x + y + z) * distortion;
  }
  if (depth > 6) {
    x = cos(x + y + z) * distortion;
  }
  if (depth > 7) {
    z = sin(x + y - z) * distortion;
  }
  if (depth > 8) {
    x = -cos(-x - y + z) * distortion;
  }
  if (depth > 9) {
    y = -sin(x - y + z) * distortion;
  }
  if (distortion != 0.0) {
    float d = distortion * 2.0;
    x /= d;
    y /= d;
    z /= d;
  }
  vec3 color = vec3(0.5 - x, 0.5 - y, 0.5 - z);
  return vec4(color, (color.x + color.y + color.z) * (1.0 / 3.0));
}

#endif /* PENUMBRA_LIB_NODES_TEXTURE_MAGIC */
