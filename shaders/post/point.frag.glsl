/* Consecutive per-pixel layers in one pass (base.py's PointEffect). POINT_COUNT layers; layer
 * i is the function POINT_FN_i, its data point[4 i] ... point[4 i + 3], its mix in
 * point[4 i + 3].w. Each step is what a pass of its own computes: the layer's input
 * sanitised as post_source() reads it, then blended as post_mix() does. */

vec4 point_step(vec4 c, vec4 effected, int layer)
{
  float m = point[4 * layer + 3].v.w;
  return (m >= 1.0) ? effected : mix(c, effected, m);
}

/* Layer i of the pass: its input cleaned of NaN/Inf, its effect, its mix. */
#define POINT_LAYER(i, fn) c = sanitize(c); c = point_step(c, fn(c, 4 * (i)), i)

void main()
{
  vec4 c = post_source();
#if POINT_COUNT > 0
  POINT_LAYER(0, POINT_FN_0);
#endif
#if POINT_COUNT > 1
  POINT_LAYER(1, POINT_FN_1);
#endif
#if POINT_COUNT > 2
  POINT_LAYER(2, POINT_FN_2);
#endif
#if POINT_COUNT > 3
  POINT_LAYER(3, POINT_FN_3);
#endif
#if POINT_COUNT > 4
  POINT_LAYER(4, POINT_FN_4);
#endif
#if POINT_COUNT > 5
  POINT_LAYER(5, POINT_FN_5);
#endif
#if POINT_COUNT > 6
  POINT_LAYER(6, POINT_FN_6);
#endif
#if POINT_COUNT > 7
  POINT_LAYER(7, POINT_FN_7);
#endif
  out_color = c;
}
