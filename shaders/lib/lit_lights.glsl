// requires: lib/lights.glsl lib/lit_debug.glsl lib/shadow_filters.glsl lib/lit_surface.glsl lib/lit_terminator.glsl lib/lit_bsdf.glsl lib/lit_world.glsl lib/lit_settle.glsl lib/volumes.glsl lib/sheen.glsl lib/subsurface.glsl
#ifndef PENUMBRA_LIB_LIT_LIGHTS
#define PENUMBRA_LIB_LIT_LIGHTS

/* The lights on the surface. Each light's shadow is looked up once, then every lobe's BSDF
 * under it. The lit pass pays only for what it uses: lights sampled over their extent come
 * first (frame.sampled_count, PCSS of their per-sample size), then the other lights with a
 * shadow map (up to frame.shadowed_count, the scene's filter), then lights without a map (no
 * filter code); a scene without lights runs no loop. With several local lights each pixel
 * loops only over the lights its screen bin lists (LIGHT_BINS); with a few lights and no bins
 * the counts are compiled in and each light is called by its constant index (UNROLLED_LIGHTS).
 * One entry point, lights_on(), covers the three. */

/* Add light i's contribution. ``filter_id`` is a literal at each call (FILTER_* or NO_SHADOW), so
 * the compiler keeps a shadow filter only where a light has a map, and only that one.
 * ``arriving`` / ``unshadowed``: the Shadow pass's sums, direct light that arrives over direct
 * light that would arrive unshadowed, each light weighted by the luminance of its irradiance
 * here (by the heavier lobe's cosine). */
void add_light(int i, const int filter_id, Surface s, inout vec3 color, inout float arriving,
               inout float unshadowed)
{
#if LIGHT_LINKING
  /* Light linking: this object's bit of light i (engine/frame/draw_list.py, light_masks). */
  if (((uint(light_mask[i >> 5]) >> uint(i & 31)) & 1u) == 0u) {
    return;
  }
#endif
#if DEBUG_LIT
  debug_lights += 1.0;
#endif
  LightData L = lights[i];
  vec3 to_light;
  float irradiance;
  light_incident(L, s.P, to_light, irradiance);
  float NdotL[NODE_LOBES], cosines[NODE_LOBES];
  bool faces = false;
  for (int k = 0; k < NODE_LOBES; k++) {
    NdotL[k] = dot(s.lobe[k].N, to_light);
    cosines[k] = (NdotL[k] > 0.0) ? cosine_term(NdotL[k]) : 0.0;
    faces = faces || NdotL[k] > 0.0;
  }
#if LIGHT_PASS == LIGHT_PASS_SUBSURFACE && !WORLD_RATIO
  if (filter_id != NO_SHADOW && irradiance > 0.0) {
    color += (L.color * irradiance) * subsurface_through(s, L, to_light); /* from behind (lib/subsurface.glsl) */
  }
#elif LIGHT_PASS == LIGHT_PASS_SUBSURFACE
  if (filter_id != NO_SHADOW && irradiance > 0.0 && L.world == 0) { /* the ratio's directions carry none */
    color += (L.color * irradiance) * subsurface_through(s, L, to_light); /* from behind (lib/subsurface.glsl) */
  }
#endif
  if (!faces || irradiance <= 0.0) {
#if SETTLE_TEST
    settle_unreached(L, s, to_light, irradiance, filter_id); /* other points may reach it */
#endif
    return;
  }
  float weight = dot(L.color, vec3(0.2126, 0.7152, 0.0722)) * irradiance * cosines[heavier_lobe(s)];
  float NgdotL = dot(s.Ng, to_light);
  float visibility = (filter_id == NO_SHADOW) ? 1.0 :
                     (NgdotL <= 0.0 || facet_turned(s, L, to_light)) ? 0.0 :
                                                                       shadow_visibility(L, shadow_point(s, to_light, NgdotL), s.Ng, s.Nf, NgdotL, dot(s.Nf, to_light), filter_id);
#if SETTLE_TEST
  visibility = settle_reached(L, s, to_light, irradiance, NgdotL, visibility, filter_id);
#endif
#if WORLD_RATIO
  if (L.world != 0) {
    world_direction(s, L, to_light, irradiance, visibility, NdotL, cosines);
    return;
  }
#endif
#if WORLD_LIGHTS
  /* A direction of the world's light carrying its whole light (with light portals: the SH
   * light is then not given, frame/world/directions.py); not part of the Shadow pass (the
   * lights' alone, as Cycles'). */
  float world_light = float(L.world);
#else
  const float world_light = 0.0;
#endif
  unshadowed += weight * (1.0 - world_light);
  arriving += weight * visibility * (1.0 - world_light);
  vec3 reflected = vec3(0.0);
  for (int k = 0; k < NODE_LOBES; k++) {
    if (NdotL[k] > 0.0) {
      vec3 f = lobe_brdf(s.lobe[k], s.V, to_light, NdotL[k], L);
#if LIGHT_PASS == LIGHT_PASS_DIFFUSE || LIGHT_PASS == LIGHT_PASS_SUBSURFACE
      f = min(f, s.lobe[k].albedo / M_PI * L.diffuse_factor); /* its diffuse term (the specular's >= 0) */
#elif LIGHT_PASS == LIGHT_PASS_GLOSSY
      f = max(f - s.lobe[k].albedo / M_PI * L.diffuse_factor, vec3(0.0)); /* the rest: its specular */
#endif
      reflected += (s.lobe[k].weight * cosines[k]) * f;
    }
  }
#if DEBUG_TERM == 4 || DEBUG_TERM == 5
  vec3 layer = vec3(0.0); /* the Coat Light (4) or Sheen Light (5) view's layer alone */
#endif
#if NODE_SHEEN
  /* The sheen over the lobes (lib/sheen.glsl): what they keep under it, and its own light (a
   * diffuse lobe in Blender's passes). */
  reflected *= s.sheen.below;
#  if LIGHT_PASS == 0 || LIGHT_PASS == LIGHT_PASS_DIFFUSE || LIGHT_PASS == LIGHT_PASS_GROUP
  vec3 sheen = sheen_light(s.sheen, to_light) * L.diffuse_factor;
  reflected += sheen;
#    if DEBUG_TERM == 5
  layer = sheen;
#    endif
#  endif
#endif
#if NODE_COAT
  /* The coat over the lobes (lit_bsdf.glsl): what reaches them under it, and its own reflection
   * (a glossy lobe: the Glossy passes, not the Diffuse ones). */
  reflected *= s.coat.below;
#  if DEBUG_TERM == 5
  layer *= s.coat.below;
#  endif
#  if LIGHT_PASS == 0 || LIGHT_PASS == LIGHT_PASS_GLOSSY || LIGHT_PASS == LIGHT_PASS_GROUP
  float NcdotL = dot(s.coat.N, to_light);
  if (NcdotL > 0.0) {
    vec3 coat = vec3(coat_brdf(s.coat, s.V, to_light, NcdotL) * NcdotL * L.specular_factor);
    reflected += coat;
#    if DEBUG_TERM == 4
    layer = coat;
#    endif
  }
#  endif
#endif
#if VOLUMES
  /* What the media between here and the light let through (features/volumes.py). */
  reflected *= light_transmittance(s.P, L, to_light);
#endif
  vec3 added = (L.color * visibility) * irradiance * reflected;
  color += added;
#if DEBUG_TERM == 4 || DEBUG_TERM == 5
#  if VOLUMES
  layer *= light_transmittance(s.P, L, to_light);
#  endif
  debug_term += (L.color * visibility) * irradiance * layer;
#endif
#if DEBUG_TERM == 1
  debug_term += world_light * added;
#endif
}

/* Every light that may reach this pixel, each with its filter. */
void lights_on(Surface s, inout vec3 color, inout float arriving, inout float unshadowed)
{
#if LIGHT_BINS
  /* Only the lights this pixel's screen bin lists (engine/shadows/light_bins.py): word w of the
   * bin holds lights w * LIGHT_WORD_BITS + bit, as exact small integers in a float channel.
   * One loop per class of light (sampled, with a map, without) walks the set bits of all four
   * words in order. On llvmpipe a loop's body runs at least once (masked) even when no pixel
   * has work in it, so classes no light of the frame is in are not compiled (HAS_*), and the
   * words share one loop rather than one loop each. */
#  if LIGHT_WORDS != 4
#    error "the bin loops below read four words"
#  endif
  uvec4 words = uvec4(texelFetch(light_bins, ivec2(gl_FragCoord.xy) / LIGHT_BIN_SIZE, 0));
  uvec4 sampled_mask = uvec4(frame.sampled_mask), shadowed_mask = uvec4(frame.shadowed_mask);
#  define BIN_LOOP(BITS, FILTER) \
    { \
      uvec4 bits = (BITS); \
      while (any(notEqual(bits, uvec4(0u)))) { \
        int w = (bits.x != 0u) ? 0 : (bits.y != 0u) ? 1 : (bits.z != 0u) ? 2 : 3; \
        uint word = bits[w]; \
        bits[w] = word & (word - 1u); \
        add_light(w * LIGHT_WORD_BITS + findLSB(word), FILTER, s, color, arriving, unshadowed); \
      } \
    }
#  if SAMPLED_LIGHTS
  BIN_LOOP(words & sampled_mask, FILTER_PCSS)
#  endif
#  if HAS_SHADOWED
  BIN_LOOP(words & shadowed_mask & ~sampled_mask, SHADOW_FILTER)
#  endif
#  if HAS_UNSHADOWED
  BIN_LOOP(words & ~shadowed_mask, NO_SHADOW)
#  endif
#elif UNROLLED_LIGHTS
  /* The light counts are compiled in (frame/programs.py UNROLLED_LIGHTS): one call per light,
   * each reading its LightData at a constant offset; the counts fold each call to its filter. */
#  define LIGHT_FILTER(k) \
    ((k) < SAMPLED_COUNT ? FILTER_PCSS : (k) < SHADOWED_COUNT ? SHADOW_FILTER : NO_SHADOW)
#  if LIGHT_COUNT > 0
  add_light(0, LIGHT_FILTER(0), s, color, arriving, unshadowed);
#  endif
#  if LIGHT_COUNT > 1
  add_light(1, LIGHT_FILTER(1), s, color, arriving, unshadowed);
#  endif
#  if LIGHT_COUNT > 2
  add_light(2, LIGHT_FILTER(2), s, color, arriving, unshadowed);
#  endif
#  if LIGHT_COUNT > 3
  add_light(3, LIGHT_FILTER(3), s, color, arriving, unshadowed);
#  endif
#  if LIGHT_COUNT > 4
#    error "UNROLLED_LIGHTS is larger than the calls written out here"
#  endif
#else
#  if SAMPLED_LIGHTS
  for (int i = 0; i < frame.sampled_count; i++) {
    add_light(i, FILTER_PCSS, s, color, arriving, unshadowed);
  }
#  endif
#  if HAS_SHADOWED
  for (int i = frame.sampled_count; i < frame.shadowed_count; i++) {
    add_light(i, SHADOW_FILTER, s, color, arriving, unshadowed);
  }
#  endif
#  if HAS_UNSHADOWED
  for (int i = frame.shadowed_count; i < frame.light_count; i++) {
    add_light(i, NO_SHADOW, s, color, arriving, unshadowed);
  }
#  endif
#endif
}

#endif /* PENUMBRA_LIB_LIT_LIGHTS */
