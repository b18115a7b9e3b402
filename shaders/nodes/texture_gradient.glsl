// requires: nodes/texture_hash.glsl
#ifndef PENUMBRA_LIB_NODES_TEXTURE_GRADIENT
#define PENUMBRA_LIB_NODES_TEXTURE_GRADIENT

/* Blender's Gradient Texture node, of the point as given (no scale), clamped to [0, 1]:
 * Linear x; Quadratic max(x, 0)^2; Easing the cubic 3t^2 - 2t^3 of t = clamp(x, 0, 1); Diagonal
 * (x + y) / 2; Radial the angle atan2(y, x) / 2pi + 0.5; Spherical max(0.999999 - |p|, 0) and
 * Quadratic Sphere its square (the 0.999999, as Blender's, gives exactly 0 on the unit sphere).
 *
 * A non-finite coordinate reads as 0; values that overflow clamp as Blender's (a length that
 * overflows gives 0). */

/* Gradient Texture node `gradient_type`. */
#define GRADIENT_LINEAR 0
#define GRADIENT_QUADRATIC 1
#define GRADIENT_EASING 2
#define GRADIENT_DIAGONAL 3
#define GRADIENT_SPHERICAL 4
#define GRADIENT_QUADRATIC_SPHERE 5
#define GRADIENT_RADIAL 6

/* Unclamped value of the gradient. */
float texture_gradient(vec3 p, int type)
{
  if (type == GRADIENT_LINEAR) {
    return p.x;
  }
  if (type == GRADIENT_QUADRATIC) {
    float r = max(p.x, 0.0);
    return r * r;
  }
  if (type == GRADIENT_EASING) {
    float r = clamp(p.x, 0.0, 1.0);
    float t = r * r;
    return 3.0 * t - 2.0 * t * r;
  }
  if (type == GRADIENT_DIAGONAL) {
    return (p.x + p.y) * 0.5;
  }
  if (type == GRADIENT_RADIAL) {
    return atan(p.y, p.x) / 6.2831853071795864 + 0.5;
  }
  float r = max(0.999999 - sqrt(p.x * p.x + p.y * p.y + p.z * p.z), 0.0);
  if (type == GRADIENT_QUADRATIC_SPHERE) {
    return r * r;
  }
  if (type == GRADIENT_SPHERICAL) {
    return r;
  }
  return 0.0;
}

/* The node: Color in .rgb (Fac, grey), Fac in .a. */
vec4 node_tex_gradient(vec3 vector, int type)
{
  float f = clamp(texture_gradient(texture_finite(vector), type), 0.0, 1.0);
  return vec4(f, f, f, f);
}

#endif /* PENUMBRA_LIB_NODES_TEXTURE_GRADIENT */
