#ifndef SHADOW_FILTERS_GLSL
#define SHADOW_FILTERS_GLSL

/* Shadow visibility of world point P for light L (1 = lit, 0 = shadowed).
 * Each map is a square tile (params.y) of shadow_atlas holding the light's normalised depth
 * (0 near, 1 far); tiles are shadow_size.x texels wide, shadow_size.y to a row.
 * Bias is expressed in shadow-map texels so one setting holds at every scene scale:
 *   normal offset  moves P along N by shadow_params.z texels * sin(theta)
 *   constant       shadow_params.x texels of depth
 *   slope-scaled   shadow_params.y texels * tan(theta), tan clamped to 10. */
float shadow_compare(float tile, ivec2 texel, float ref)
{
  int size = int(frame.shadow_size.x);
  if (texel.x < 0 || texel.y < 0 || texel.x >= size || texel.y >= size) {
    return 1.0; /* outside the fitted frustum: nothing casts there */
  }
  int t = int(tile);
  int columns = int(frame.shadow_size.y);
  ivec2 origin = ivec2(t % columns, t / columns) * size;
  float stored = texelFetch(shadow_atlas, origin + texel, 0).r;
  return (ref <= stored) ? 1.0 : 0.0;
}

float shadow_visibility(LightData L, vec3 P, vec3 N, float NdotL)
{
  float texel_world = L.params.z;
  float depth_per_world = L.params.w;
  float cos_t = clamp(NdotL, 1e-4, 1.0);
  float sin_t = sqrt(1.0 - cos_t * cos_t);
  float tan_t = min(sin_t / cos_t, 10.0);
  vec3 Po = P + N * (frame.shadow_params.z * texel_world * sin_t);
  vec4 sc = L.shadow_matrix * vec4(Po, 1.0);
  vec3 s = sc.xyz / sc.w;
  if (s.z >= 1.0) {
    return 1.0;
  }
  float bias = (frame.shadow_params.x + frame.shadow_params.y * tan_t) * texel_world *
               depth_per_world;
  float ref = s.z - bias;
  float map_size = frame.shadow_size.x;
  vec2 st = s.xy * map_size;
#if SHADOW_FILTER == FILTER_NONE
  return shadow_compare(L.params.y, ivec2(floor(st)), ref);
#elif SHADOW_FILTER == FILTER_PCF
  float lit = 0.0;
  float spacing = frame.shadow_params.w;
  for (int i = 0; i < PCF_TAPS; i++) {
    vec4 tap = pcf_taps[i].v;
    lit += tap.z * shadow_compare(L.params.y, ivec2(floor(st + tap.xy * spacing)), ref);
  }
  return lit;
#else
#  error "unknown SHADOW_FILTER"
#endif
}

#endif
