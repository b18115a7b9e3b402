/* The lit pass (engine/frame/lit_pass.py): the surface's material, its lobes, the world's light
 * and every light's, with their shadows. By concern, in the libraries the program lists
 * (engine/frame/programs.py LIT; each after the ones its ``// requires:`` line names):
 *   lib/lit_debug.glsl       what the debug views record (declared only in their variants)
 *   lib/lit_surface.glsl     the Surface and its lobes; point, view, normals, normal maps, hair
 *   lib/lit_terminator.glsl  Shadow Terminator: where a light's shadow is looked up, the cosine
 *   lib/lit_bsdf.glsl        the Principled layering: lobe_setup, lobe_brdf, env_brdf
 *   lib/lit_world.glsl       the world's SH light, its occlusion (WORLD_AO) and ratio (WORLD_RATIO)
 *   lib/refraction.glsl      what a transmissive surface shows through it (TRANSMISSION)
 *   lib/lit_settle.glsl      the settle test's flags (SETTLE_TEST)
 *   lib/lit_lights.glsl      add_light (one shadow lookup, every lobe) and lights_on (the loops)
 *   lib/lit_outputs.glsl     surface_color and write_passes: what a variant writes
 *   (a compiled node tree's code)
 *   lib/lit_inputs.glsl      the material at the fragment and the surface set up from it
 * The material comes from the MaterialData block and, per variant (programs.material_defines),
 * image textures, a colour attribute, a normal map, the alpha mode, or a compiled node tree.
 *
 * Three entry shaders share these libraries (programs.ENTRY_PARTS): this one, the surface's
 * colour; lit_settle.frag.glsl, the settle test's flags (SETTLE_TEST); lit_debug.frag.glsl, a
 * debug view's values (DEBUG_LIT, DEBUG_TERM). This one writes, per variant:
 *   default        colour (+ Shadow, Normal and Depth with AUX_OUTPUTS, Emission with
 *                  EMISSION_OUTPUT; the ratio's targets with WORLD_RATIO_OUT)
 *   EMISSION_ONLY  the Emission pass alone, over the z-buffer the lit pass left */

#ifndef CLIP_PLANE
#  define CLIP_PLANE 0
#endif

void main()
{
  MaterialInputs m = material_inputs();
  /* Decided here, discarded at the end (lib/lit_inputs.glsl coverage_discards). */
  bool dropped = coverage_discards(m.coverage);
#if CLIP_PLANE
  /* A Plane probe's capture (engine/frame/features/planar.py): nothing under the mirror
   * (discarded at the end, as the coverage: never ahead of the lights' loops). */
  dropped = dropped || dot(vec4(v_world, 1.0), frame.clip_plane) < 0.0;
#endif
#if EMISSION_ONLY
  /* The Emission pass drawn apart, over the z-buffer the lit pass left (a frame whose other
   * targets leave its own no room: lit_pass.py). */
  if (dropped) {
    discard;
  }
  out_color = surface_color(m.emission, 1.0);
  return;
#endif

  vec2 ab[NODE_LOBES];
  Surface s = surface_setup(m, ab);
#if TRANSMISSION
  /* The share of the dielectric's diffuse that is light from behind instead. */
  float transmitted = transmission_share(m.transmission, m.metal);
  s.lobe[0].albedo *= 1.0 - transmitted;
#endif

  /* The world's light, the lights', the bounce. */
  vec3 color = surface_world_light(s, ab);
  float arriving = 0.0, unshadowed = 0.0;
#if LIGHT_PASS == 0 || LIGHT_PASS == LIGHT_PASS_DIFFUSE || LIGHT_PASS == LIGHT_PASS_GLOSSY || \
    LIGHT_PASS == LIGHT_PASS_GROUP || LIGHT_PASS == LIGHT_PASS_SUBSURFACE
  lights_on(s, color, arriving, unshadowed);
#endif
#if TRANSMISSION && (LIGHT_PASS == 0 || LIGHT_PASS == LIGHT_PASS_TRANSMISSION)
  color += transmitted * surface_refraction(s, m.base.rgb, ab[0]);
#endif
#if INDIRECT_RSM && (LIGHT_PASS == 0 || LIGHT_PASS == LIGHT_PASS_DIFFUSE_INDIRECT || LIGHT_PASS == LIGHT_PASS_SUBSURFACE)
  /* One diffuse bounce from the lights' reflective shadow maps (lib/indirect_rsm.glsl). */
  color += surface_bounce(s);
#endif
#if WORLD_RATIO && (WORLD_RATIO_OUT != 1 || LIGHT_PASS == LIGHT_PASS_SUBSURFACE)
  /* No film sums for this surface (a blended one, or the light below one that spreads over its
   * neighbours before the film takes it): its own ratio within this sample (of the world's light
   * the variant carries: a light pass's lobe alone). */
#  if LIGHT_PASS == LIGHT_PASS_DIFFUSE || LIGHT_PASS == LIGHT_PASS_SUBSURFACE
  world_s = vec3(0.0);
#  elif LIGHT_PASS == LIGHT_PASS_GLOSSY
  world_d = vec3(0.0);
#  elif LIGHT_PASS == LIGHT_PASS_GROUP && LIGHT_GROUP_WORLD
  /* the world's light whole */
#  elif LIGHT_PASS != 0
  world_d = world_s = vec3(0.0);
#  endif
  color = world_ratio_apply(vec4(color, 1.0), world_d, world_s, world_sums).rgb;
#endif
  if (dropped) {
    discard;
  }
#if LIGHT_PASS == LIGHT_PASS_GROUP
  m.emission *= group_emission; /* 1 where the object is in the group */
#elif LIGHT_PASS != 0
  m.emission = vec3(0.0); /* the Emission pass's */
#endif
#if LIGHT_PASS == LIGHT_PASS_SUBSURFACE && NODE_SSS
  /* How that light leaves towards the viewer, and what the diffusion reads besides it
   * (lib/subsurface.glsl). */
  vec3 exit = subsurface_exit(s, m.sss_exit);
  color *= exit;
  subsurface_outputs(s, m.sss, exit);
#elif LIGHT_PASS == LIGHT_PASS_SUBSURFACE
  subsurface_outputs(s, vec4(0.0), vec3(1.0));
#endif
  write_passes(surface_color(color + m.emission, m.coverage), s, arriving, unshadowed, m.emission, HOLDOUT == 0);
}
