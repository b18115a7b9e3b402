/* The settle test (engine/frame/features/settling.py, lib/lit_settle.glsl): the lit pass's libraries over
 * the surfaces a frame's pilot sample drew, lights at their centres, writing per pixel whether
 * a later sample could change it through a light, and how far its light is from the light's
 * average over each extent (settle_flags). No colour, no passes. */

void main()
{
  MaterialInputs m = material_inputs();
  vec2 ab[NODE_LOBES];
  Surface s = surface_setup(m, ab);
  vec3 world_term = surface_world_light(s, ab); /* the world's light, unshadowed */
  vec3 color = world_term;
  float arriving = 0.0, unshadowed = 0.0;
  lights_on(s, color, arriving, unshadowed); /* add_light records each light's flags */
#if ALPHA_MODE != 0
  /* Never drawn; where it covers some samples, it marks the pixel unsettled. Discarded at the
   * end, not before the lights' loops (lib/lit_inputs.glsl coverage_discards). */
  if (m.coverage <= 0.0) {
    discard;
  }
#endif
#if SSR_SETTLE
  /* A lobe later samples trace (features/reflections.py) changes with every sample. */
  settle_unstable = settle_unstable || world_traced;
#endif
#if NODE_COAT
  /* A coat's highlight is not in the test's lobes: it keeps sampling. */
  settle_unstable = settle_unstable || s.coat.weight > 0.0;
#endif
#if NODE_ANISO
  /* An anisotropic lobe's world light is drawn anew each sample (lib/anisotropy.glsl). */
  for (int k = 0; k < NODE_LOBES; k++) {
    settle_unstable = settle_unstable || s.lobe[k].ax != s.lobe[k].ay;
  }
#endif
#if NODE_SHEEN
  /* Nor is the sheen's light. */
  settle_unstable = settle_unstable || s.sheen.ltc.z > 0.0;
#endif
#if NODE_SSS
  /* Nor is the light below the surface, spread anew each sample (features/subsurface.py). */
  settle_unstable = settle_unstable || m.sss.w > 0.0;
#endif
#if TRANSMISSION
  /* What a transmissive surface shows through it (features/refraction.py) is traced anew
   * every sample. */
  settle_unstable = settle_unstable || material.transmission > 0.0;
#endif
  out_color = settle_flags(world_term, m.coverage);
}
