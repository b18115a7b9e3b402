// requires: nodes/texture_hash.glsl
#ifndef PENUMBRA_LIB_NODES_TEXTURE_CHECKER
#define PENUMBRA_LIB_NODES_TEXTURE_CHECKER

/* Blender's Checker Texture node: unit cubes of the scaled point alternate Color1 (Fac 1) and
 * Color2 (Fac 0) by the parity of their integer coordinates. Like Blender, the point is nudged,
 * (p + 1e-6) * 0.999999, so that faces on integer coordinates fall on one side.
 *
 * Cell numbers convert to int as x86 does (INT_MIN, even, out of range); a non-finite
 * coordinate, or one that overflows with Scale, reads as 0. */

/* 1 or 0 on the already scaled point p. */
float texture_checker(vec3 p)
{
  p = (p + 0.000001) * 0.999999;
  int xi = texture_float_to_int(floor(p.x)) & 1;
  int yi = texture_float_to_int(floor(p.y)) & 1;
  int zi = texture_float_to_int(floor(p.z)) & 1;
  return ((xi == yi) == (zi == 1)) ? 1.0 : 0.0;
}

/* The node: Color in .rgb, Fac in .a. */
vec4 node_tex_checker(vec3 vector, vec3 color1, vec3 color2, float scale)
{
  float f = texture_checker(texture_finite(texture_finite(vector) * scale));
  return vec4((f == 1.0) ? color1 : color2, f);
}

#endif /* PENUMBRA_LIB_NODES_TEXTURE_CHECKER */
