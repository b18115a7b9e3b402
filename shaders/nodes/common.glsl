// requires:
#ifndef PENUMBRA_LIB_NODES_COMMON
#define PENUMBRA_LIB_NODES_COMMON

/* Helpers every shader-node family shares: safe arithmetic as Blender's node maths defines
 * it (a division by zero gives 0, a power of a negative base needs an integer exponent) and
 * the colour models (HSV, HSL) of Blender's colour nodes. Each function has a numpy twin in
 * devkit/node_reference.py. */

#define NODE_PI 3.14159265358979323846

/* The most octaves a fractal texture sums (Noise, Voronoi): Blender clamps Detail to 15. Every
 * octave loop is bounded by this constant as well as by its Detail, so no input (NaN, 1e30,
 * whose int() GLSL leaves undefined) can make a loop without end. */
#define NODE_MAX_OCTAVE 15

/* Detail clamped to [0, 15] before it becomes a count; NaN gives 0 (clamp() leaves NaN to
 * the implementation, and int(NaN) is undefined). */
float node_detail(float detail)
{
  return (detail >= 0.0) ? min(detail, float(NODE_MAX_OCTAVE)) : 0.0;
}

float node_safe_divide(float a, float b)
{
  return (b != 0.0) ? a / b : 0.0;
}

vec3 node_safe_divide3(vec3 a, vec3 b)
{
  return vec3(node_safe_divide(a.x, b.x), node_safe_divide(a.y, b.y), node_safe_divide(a.z, b.z));
}

/* x^y, defined for a negative base with an integer exponent (Blender's compatible power). */
float node_pow(float x, float y)
{
  if (y == 0.0) {
    return 1.0;
  }
  if (x < 0.0) {
    float m = mod(-y, 2.0);
    return (m == 0.0) ? pow(-x, y) : ((m == 1.0) ? -pow(-x, y) : 0.0);
  }
  if (x == 0.0) {
    return 0.0;
  }
  return pow(x, y);
}

vec3 node_safe_normalize(vec3 v)
{
  float l = length(v);
  return (l != 0.0 && !isinf(l)) ? v / l : vec3(0.0);
}

/* Euler XYZ angles as a rotation matrix (Blender's order: X first, then Y, then Z). */
mat3 node_euler_to_mat3(vec3 e)
{
  float cx = cos(e.x), cy = cos(e.y), cz = cos(e.z);
  float sx = sin(e.x), sy = sin(e.y), sz = sin(e.z);
  return mat3(cy * cz, cy * sz, -sy,
              sy * sx * cz - cx * sz, sy * sx * sz + cx * cz, cy * sx,
              sy * cx * cz + sx * sz, sy * cx * sz - sx * cz, cy * cx);
}

vec4 node_rgb_to_hsv(vec4 rgb)
{
  float cmax = max(rgb.r, max(rgb.g, rgb.b));
  float cmin = min(rgb.r, min(rgb.g, rgb.b));
  float delta = cmax - cmin;
  float s = (cmax != 0.0) ? delta / cmax : 0.0;
  float h = 0.0;
  if (s != 0.0) {
    vec3 c = (vec3(cmax) - rgb.rgb) / delta;
    if (rgb.r == cmax) {
      h = c.b - c.g;
    }
    else if (rgb.g == cmax) {
      h = 2.0 + c.r - c.b;
    }
    else {
      h = 4.0 + c.g - c.r;
    }
    h /= 6.0;
    if (h < 0.0) {
      h += 1.0;
    }
  }
  return vec4(h, s, cmax, rgb.a);
}

vec4 node_hsv_to_rgb(vec4 hsv)
{
  float h = hsv.x, s = hsv.y, v = hsv.z;
  vec3 rgb = vec3(v);
  if (s != 0.0) {
    if (h == 1.0) {
      h = 0.0;
    }
    h *= 6.0;
    float i = floor(h);
    float f = h - i;
    float p = v * (1.0 - s), q = v * (1.0 - s * f), t = v * (1.0 - s * (1.0 - f));
    rgb = (i == 0.0) ? vec3(v, t, p) :
          (i == 1.0) ? vec3(q, v, p) :
          (i == 2.0) ? vec3(p, v, t) :
          (i == 3.0) ? vec3(p, q, v) :
          (i == 4.0) ? vec3(t, p, v) :
                       vec3(v, p, q);
  }
  return vec4(rgb, hsv.a);
}

vec4 node_rgb_to_hsl(vec4 rgb)
{
  float cmax = max(rgb.r, max(rgb.g, rgb.b));
  float cmin = min(rgb.r, min(rgb.g, rgb.b));
  float l = min(1.0, (cmax + cmin) * 0.5);
  float h = 0.0, s = 0.0;
  if (cmax != cmin) {
    float d = cmax - cmin;
    s = (l > 0.5) ? d / (2.0 - cmax - cmin) : d / (cmax + cmin);
    if (cmax == rgb.r) {
      h = (rgb.g - rgb.b) / d + ((rgb.g < rgb.b) ? 6.0 : 0.0);
    }
    else if (cmax == rgb.g) {
      h = (rgb.b - rgb.r) / d + 2.0;
    }
    else {
      h = (rgb.r - rgb.g) / d + 4.0;
    }
  }
  return vec4(h / 6.0, s, l, rgb.a);
}

vec4 node_hsl_to_rgb(vec4 hsl)
{
  float h = hsl.x, s = hsl.y, l = hsl.z;
  vec3 n = clamp(vec3(abs(h * 6.0 - 3.0) - 1.0, 2.0 - abs(h * 6.0 - 2.0), 2.0 - abs(h * 6.0 - 4.0)), 0.0, 1.0);
  float chroma = (1.0 - abs(2.0 * l - 1.0)) * s;
  return vec4((n - 0.5) * chroma + l, hsl.a);
}

/* Blender's implicit socket conversions. */
float node_color_to_float(vec4 c)
{
  return dot(c.rgb, vec3(0.2126, 0.7152, 0.0722));
}

float node_vector_to_float(vec3 v)
{
  return (v.x + v.y + v.z) / 3.0;
}

#endif /* PENUMBRA_LIB_NODES_COMMON */
