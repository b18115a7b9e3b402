// requires: nodes/common.glsl
#ifndef PENUMBRA_LIB_NODES_CONVERTER
#define PENUMBRA_LIB_NODES_CONVERTER

/* Converter nodes (Blender manual: Map Range, Clamp, Color Ramp). The Color Ramp's stops are
 * constants of the material (its node_constants block, two vec4 each: colour, then position
 * in x), read from ``first``; their count, interpolation and colour mode are compiled in. */

float node_smootherstep(float e0, float e1, float x)
{
  x = clamp(node_safe_divide(x - e0, e1 - e0), 0.0, 1.0);
  return x * x * x * (x * (x * 6.0 - 15.0) + 10.0);
}

/* Map Range (Float): 0 Linear, 1 Stepped, 2 Smooth Step, 3 Smoother Step. */
float node_map_range(const int type, const bool clamped, float v, float from_min, float from_max, float to_min,
                     float to_max, float steps)
{
  if (from_max == from_min) {
    return 0.0;
  }
  float f = (v - from_min) / (from_max - from_min);
  if (type == 1) {
    f = (steps > 0.0) ? floor(f * (steps + 1.0)) / steps : 0.0;
  }
  else if (type == 2) {
    f = (from_min > from_max) ? 1.0 - smoothstep(from_max, from_min, v) : smoothstep(from_min, from_max, v);
  }
  else if (type == 3) {
    f = (from_min > from_max) ? 1.0 - node_smootherstep(from_max, from_min, v) :
                                node_smootherstep(from_min, from_max, v);
  }
  float r = to_min + f * (to_max - to_min);
  if (clamped && type < 2) {
    r = (to_min > to_max) ? clamp(r, to_max, to_min) : clamp(r, to_min, to_max);
  }
  return r;
}

/* Clamp: 0 Min Max, 1 Range (min and max in either order). */
float node_clamp(const int type, float v, float lo, float hi)
{
  if (type == 1 && lo > hi) {
    return clamp(v, hi, lo);
  }
  return min(max(v, lo), hi);
}

float node_hue_interp(const int hue_mode, float fm, float f, float h1, float h2)
{
  h1 = (h1 < 1.0) ? h1 : h1 - 1.0;
  h2 = (h2 < 1.0) ? h2 : h2 - 1.0;
  int m = 0;
  if (hue_mode == 0) { /* Near */
    m = (h1 < h2 && h2 - h1 > 0.5) ? 1 : (h1 > h2 && h2 - h1 < -0.5) ? 2 : 0;
  }
  else if (hue_mode == 1) { /* Far */
    m = (h1 == h2) ? 1 : (h1 < h2 && h2 - h1 < 0.5) ? 1 : (h1 > h2 && h2 - h1 > -0.5) ? 2 : 0;
  }
  else if (hue_mode == 2) { /* Clockwise */
    m = (h1 < h2) ? 1 : 0;
  }
  else { /* Counter-clockwise */
    m = (h1 > h2) ? 2 : 0;
  }
  float h = (m == 1) ? fm * (h1 + 1.0) + f * h2 : (m == 2) ? fm * h1 + f * (h2 + 1.0) : fm * h1 + f * h2;
  return (m != 0 && h >= 1.0) ? h - 1.0 : h;
}

#define NODE_RAMP_COLOR(i) node_constants[first + 2 * (i)].v
#define NODE_RAMP_POS(i) node_constants[first + 2 * (i) + 1].v.x

/* Color Ramp as Blender evaluates a colour band. interp: 0 Constant, 1 Linear, 2 Ease,
 * 3 Cardinal, 4 B-Spline; mode: 0 RGB, 1 HSV, 2 HSL; hue_mode: 0 Near, 1 Far, 2 CW, 3 CCW. */
vec4 node_color_ramp(float x, const int first, const int count, const int interp, const int mode,
                     const int hue_mode)
{
  int ip = (mode == 0) ? interp : 1;
  if (count == 1 || (x <= NODE_RAMP_POS(0) && ip <= 2)) {
    return NODE_RAMP_COLOR(0);
  }
  int a = 0;
  for (; a < count; a++) {
    if (NODE_RAMP_POS(a) > x) {
      break;
    }
  }
  /* i1: the first stop past x (the last one past the end), i2 the one before it. */
  int i1 = min(a, count - 1);
  int i2 = (a == count) ? count - 1 : max(a - 1, 0);
  float p1 = NODE_RAMP_POS(i1), p2 = (a == 0) ? 0.0 : NODE_RAMP_POS(i2);
  if ((a == count && ip <= 2) || ip == 0) {
    return NODE_RAMP_COLOR(i2);
  }
  float f = (p2 != p1) ? (x - p1) / (p2 - p1) : ((a != count) ? 0.0 : 1.0);
  vec4 c1 = NODE_RAMP_COLOR(i1), c2 = NODE_RAMP_COLOR(i2);
  if (ip >= 3) {
    vec4 c0 = NODE_RAMP_COLOR((a >= count - 1) ? i1 : i1 + 1);
    vec4 c3 = NODE_RAMP_COLOR((a < 2) ? i2 : i2 - 1);
    f = clamp(f, 0.0, 1.0);
    float t2 = f * f, t3 = t2 * f;
    vec4 w;
    if (ip == 3) {
      const float fc = 0.71;
      w = vec4(-fc * t3 + 2.0 * fc * t2 - fc * f, (2.0 - fc) * t3 + (fc - 3.0) * t2 + 1.0,
               (fc - 2.0) * t3 + (3.0 - 2.0 * fc) * t2 + fc * f, fc * t3 - fc * t2);
    }
    else {
      w = vec4(-t3 / 6.0 + 0.5 * t2 - 0.5 * f + 1.0 / 6.0, 0.5 * t3 - t2 + 2.0 / 3.0,
               -0.5 * t3 + 0.5 * t2 + 0.5 * f + 1.0 / 6.0, t3 / 6.0);
    }
    return clamp(w.w * c3 + w.z * c2 + w.y * c1 + w.x * c0, 0.0, 1.0);
  }
  if (ip == 2) {
    f = f * f * (3.0 - 2.0 * f);
  }
  float fm = 1.0 - f;
  if (mode == 0) {
    return fm * c1 + f * c2;
  }
  vec4 h1 = (mode == 1) ? node_rgb_to_hsv(c1) : node_rgb_to_hsl(c1);
  vec4 h2 = (mode == 1) ? node_rgb_to_hsv(c2) : node_rgb_to_hsl(c2);
  vec4 h = vec4(node_hue_interp(hue_mode, fm, f, h1.x, h2.x), fm * h1.yzw + f * h2.yzw);
  return (mode == 1) ? node_hsv_to_rgb(h) : node_hsl_to_rgb(h);
}

#undef NODE_RAMP_COLOR
#undef NODE_RAMP_POS

#define NODE_CURVE_Y(k) node_constants[first + (k) / 4].v[(k) % 4]

/* A curve of RGB Curves / Float Curve, tabulated at ``count`` points over the x range of its
 * control points (constants from ``first``, four a row), read linearly between them; past
 * the range it continues along the curve's end slopes (head: x of the first point, 1 / the
 * range, slope before, slope after), as Blender's curves extrapolate. */
float node_curve(float x, const int first, const int count, vec4 head)
{
  float t = (x - head.x) * head.y * float(count - 1);
  if (isnan(t)) {
    return NODE_CURVE_Y(0);
  }
  if (t <= 0.0) {
    return NODE_CURVE_Y(0) + head.z * (x - head.x);
  }
  if (t >= float(count - 1)) {
    return NODE_CURVE_Y(count - 1) + head.w * (x - (head.x + 1.0 / head.y));
  }
  int i = int(floor(t));
  return mix(NODE_CURVE_Y(i), NODE_CURVE_Y(i + 1), t - float(i));
}

#undef NODE_CURVE_Y

#endif /* PENUMBRA_LIB_NODES_CONVERTER */
