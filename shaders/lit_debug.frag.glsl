/* A lit debug view (engine/frame/debug_view.py): the lit pass's libraries evaluated as for the
 * colour, writing instead what lib/lit_debug.glsl recorded, through the same film targets.
 *   DEBUG_LIT            lights evaluated, sun cascade + 1, texel density of the worst-sampled
 *                        light (LIGHT_COST, CASCADES, TEXEL_DENSITY)
 *   DEBUG_LIT, WORLD_AO  the world's visibility (WORLD_AO)
 *   DEBUG_LIT, DEBUG_REFLECTIONS  where the traced rays met the scene (REFLECTIONS)
 *   DEBUG_TERM 1         the world's light with its visibility (WORLD_LIGHT)
 *   DEBUG_TERM 2         the diffuse bounce (INDIRECT)
 *   DEBUG_TERM 3         nothing: the volumes' march adds the media's light alone (VOLUME_LIGHT)
 *   DEBUG_TERM 4         a Principled coat's reflection alone, lights and world (COAT_LIGHT)
 *   DEBUG_TERM 5         a sheen's light alone, under any coat (SHEEN_LIGHT)
 *   DEBUG_TERM 6         nothing: the subsurface diffusion adds its light alone (SUBSURFACE_LIGHT) */

void main()
{
  MaterialInputs m = material_inputs();
  bool dropped = coverage_discards(m.coverage); /* discarded at the end (lib/lit_inputs.glsl) */
  vec2 ab[NODE_LOBES];
  Surface s = surface_setup(m, ab);
#if DEBUG_LIT
  debug_dPdx = dFdx(s.P);
  debug_dPdy = dFdy(s.P);
#endif
  vec3 color = surface_world_light(s, ab);
#if DEBUG_TERM == 1
  debug_term += color;
#endif
  float arriving = 0.0, unshadowed = 0.0;
  lights_on(s, color, arriving, unshadowed); /* the world's directions add to debug_term */
#if DEBUG_TERM == 2 && INDIRECT_RSM
  debug_term += surface_bounce(s);
#endif
#if DEBUG_TERM == 1 && WORLD_RATIO && WORLD_RATIO_OUT != 1
  debug_term = world_ratio_apply(vec4(debug_term, 1.0), world_d, world_s, world_sums).rgb;
#endif

#if DEBUG_LIT && DEBUG_REFLECTIONS
  vec4 shown = vec4(debug_reflected, 0.0, 0.0, 1.0);
#elif DEBUG_LIT && WORLD_AO
  vec4 shown = vec4(debug_world_ao, 0.0, 0.0, 1.0);
#elif DEBUG_LIT
  vec4 shown = vec4(debug_lights, debug_cascade, debug_density, 1.0);
#elif HOLDOUT
  vec4 shown = vec4(0.0);
#else
  vec4 shown = vec4(debug_term, 1.0);
#endif
  if (dropped) {
    discard;
  }
  write_passes(shown, s, arriving, unshadowed, m.emission, HOLDOUT == 0 && DEBUG_LIT == 0 && DEBUG_TERM == 1);
}
