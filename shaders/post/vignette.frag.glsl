// requires: lib/common.glsl
#ifndef PENUMBRA_LIB_POST_VIGNETTE
#define PENUMBRA_LIB_POST_VIGNETTE

/* VIGNETTE as a point layer; see vignette.py's vignette_factor. point[o]: colour (xyz),
 * radius (w); point[o + 1]: softness, roundness. */
vec4 vignette_point(vec4 c, int o)
{
  vec3 color = point[o].v.xyz;
  float radius = point[o].v.w;
  float softness = point[o + 1].v.x;
  float roundness = point[o + 1].v.y;
  float aspect = target_size.x / target_size.y;
  vec2 p = (gl_FragCoord.xy / target_size - 0.5) * 2.0;
  p.x *= 1.0 + (aspect - 1.0) * roundness;
  float d = length(p);
  float f;
  if (softness <= 0.0) {
    f = (d > radius) ? 1.0 : 0.0;
  }
  else {
    float t = saturate((d - radius) / softness);
    f = t * t * (3.0 - 2.0 * t);
  }
  return vec4(mix(c.rgb, color, f), c.a);
}

#endif /* PENUMBRA_LIB_POST_VIGNETTE */
