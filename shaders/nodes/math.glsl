// requires: nodes/common.glsl
#ifndef PENUMBRA_LIB_NODES_MATH
#define PENUMBRA_LIB_NODES_MATH

/* The Math node: every operation of Blender's (the manual's Math node page), with its safe
 * definitions (a division by zero is 0, the square root of a negative number 0, ...). ``op``
 * is a literal at each call (NODE_MATH_* from engine/scene/nodetree.py), so the compiler keeps
 * only that branch. */

float node_math_wrap(float a, float b, float c)
{
  float range = b - c;
  return (range != 0.0) ? a - range * floor((a - c) / range) : c;
}

float node_math_fmod(float a, float b)
{
  return (b != 0.0) ? a - b * trunc(a / b) : 0.0;
}

float node_math_smoothmin(float a, float b, float c)
{
  if (c != 0.0) {
    float h = max(c - abs(a - b), 0.0) / c;
    return min(a, b) - h * h * h * c * (1.0 / 6.0);
  }
  return min(a, b);
}

float node_math_power(float a, float b)
{
  if (a >= 0.0) {
    return node_pow(a, b);
  }
  float f = mod(abs(b), 1.0);
  return (f > 0.999 || f < 0.001) ? node_pow(a, floor(b + 0.5)) : 0.0;
}

float node_math(const int op, float a, float b, float c)
{
  switch (op) {
    case 0: return a + b;
    case 1: return a - b;
    case 2: return a * b;
    case 3: return node_safe_divide(a, b);
    case 4: return a * b + c;
    case 5: return node_math_power(a, b);
    case 6: return (a > 0.0 && b > 0.0) ? log(a) / log(b) : 0.0;
    case 7: return (a > 0.0) ? sqrt(a) : 0.0;
    case 8: return (a > 0.0) ? inversesqrt(a) : 0.0;
    case 9: return abs(a);
    case 10: return exp(a);
    case 11: return min(a, b);
    case 12: return max(a, b);
    case 13: return (a < b) ? 1.0 : 0.0;
    case 14: return (a > b) ? 1.0 : 0.0;
    case 15: return sign(a);
    case 16: return (abs(a - b) <= max(c, 1e-5)) ? 1.0 : 0.0;
    case 17: return node_math_smoothmin(a, b, c);
    case 18: return -node_math_smoothmin(-a, -b, c);
    case 19: return floor(a + 0.5);
    case 20: return floor(a);
    case 21: return ceil(a);
    case 22: return trunc(a);
    case 23: return a - floor(a);
    case 24: return node_math_fmod(a, b);
    case 25: return (b != 0.0) ? a - floor(a / b) * b : 0.0;
    case 26: return node_math_wrap(a, b, c);
    case 27: return floor(node_safe_divide(a, b)) * b;
    case 28: return (b != 0.0) ? abs(fract((a - b) / (b * 2.0)) * b * 2.0 - b) : 0.0;
    case 29: return sin(a);
    case 30: return cos(a);
    case 31: return tan(a);
    case 32: return (a <= 1.0 && a >= -1.0) ? asin(a) : 0.0;
    case 33: return (a <= 1.0 && a >= -1.0) ? acos(a) : 0.0;
    case 34: return atan(a);
    case 35: return atan(a, b);
    case 36: return sinh(a);
    case 37: return cosh(a);
    case 38: return tanh(a);
    case 39: return a * (NODE_PI / 180.0);
    case 40: return a * (180.0 / NODE_PI);
  }
  return 0.0;
}

#endif /* PENUMBRA_LIB_NODES_MATH */
