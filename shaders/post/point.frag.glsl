/* Consecutive per-pixel layers in one pass (base.py's PointEffect). POINT_COUNT layers; layer
 * i is the function POINT_FN_i, its data point[4 i] ... point[4 i + 3], its mix in
 * point[4 i + 3].w. Each step is what a pass of its own computes: the layer's input
 * sanitised as post_source() reads it, then blended as post_mix() does. */

vec4 point_step(vec4 c, vec4 effected, int layer)
{
  float m = point[4 * layer + 3].v.w;
  return (m >= 1.0) ? effected : mix(c, effected, m);
}

void main()
{
  vec4 c = post_source();
#if POINT_COUNT > 0
  c = point_step(c, POINT_FN_0(c, 0), 0);
#endif
#if POINT_COUNT > 1
  c = sanitize(c);
  c = point_step(c, POINT_FN_1(c, 4), 1);
#endif
#if POINT_COUNT > 2
  c = sanitize(c);
  c = point_step(c, POINT_FN_2(c, 8), 2);
#endif
#if POINT_COUNT > 3
  c = sanitize(c);
  c = point_step(c, POINT_FN_3(c, 12), 3);
#endif
#if POINT_COUNT > 4
  c = sanitize(c);
  c = point_step(c, POINT_FN_4(c, 16), 4);
#endif
#if POINT_COUNT > 5
  c = sanitize(c);
  c = point_step(c, POINT_FN_5(c, 20), 5);
#endif
#if POINT_COUNT > 6
  c = sanitize(c);
  c = point_step(c, POINT_FN_6(c, 24), 6);
#endif
#if POINT_COUNT > 7
  c = sanitize(c);
  c = point_step(c, POINT_FN_7(c, 28), 7);
#endif
  out_color = c;
}
