// requires:
#ifndef PENUMBRA_LIB_POST_SEPIA
#define PENUMBRA_LIB_POST_SEPIA

/* SEPIA as a point layer (see sepia.py). point[o], point[o + 1], point[o + 2]: the rows of
 * SEPIA_MATRIX in xyz; point[o].w: amount. */
vec4 sepia_point(vec4 c, int o)
{
  vec3 s = vec3(dot(point[o].v.xyz, c.rgb), dot(point[o + 1].v.xyz, c.rgb), dot(point[o + 2].v.xyz, c.rgb));
  return vec4(mix(c.rgb, s, point[o].v.w), c.a);
}

#endif /* PENUMBRA_LIB_POST_SEPIA */
