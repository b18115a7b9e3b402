// requires: lib/lit_surface.glsl lib/lit_world.glsl
#ifndef PENUMBRA_LIB_LIT_OUTPUTS
#define PENUMBRA_LIB_LIT_OUTPUTS

/* What a lit variant writes besides its colour (lit.frag.glsl, lit_debug.frag.glsl): the
 * Shadow, Normal and Depth passes (AUX_OUTPUTS), the Emission pass (EMISSION_OUTPUT), the world
 * ratio's targets (WORLD_RATIO_OUT, lit_world.glsl) and the shading count (COUNT_SHADED). */

/* The colour a surface writes: nothing in a hole (Object > Visibility > Holdout), premultiplied
 * by its coverage where it is blended over what is behind (ALPHA_MODE 2), else opaque. */
vec4 surface_color(vec3 color, float coverage)
{
#if HOLDOUT
  return vec4(0.0);
#elif ALPHA_MODE == 2
  float a = clamp(coverage, 0.0, 1.0);
  return vec4(color * a, a);
#else
  return vec4(color, 1.0);
#endif
}

/* Write ``color`` and the variant's other targets. ``arriving`` / ``unshadowed``: the Shadow
 * pass's sums (add_light); ``world``: the colour carries the world's SH light (none in a hole,
 * nor in a debug view's values other than the world's light). */
void write_passes(vec4 color, Surface s, float arriving, float unshadowed, vec3 emission, bool world)
{
  out_color = color;
#if AUX_OUTPUTS
  /* A ratio of weighted sums lies in [0, 1] but for rounding (a division need not be
   * correctly rounded: w / w may be 1.0000001). */
  out_shadow = (unshadowed > 0.0) ? clamp(arriving / unshadowed, 0.0, 1.0) : 1.0;
  /* The heavier lobe's world-space shading normal, facing the camera (Normal pass); w: view
   * depth (Depth pass). */
  out_normal = vec4(s.lobe[heavier_lobe(s)].N, v_view_depth);
#endif
#if EMISSION_OUTPUT && HOLDOUT
  out_emission = vec4(0.0);
#elif EMISSION_OUTPUT
  out_emission = vec4(emission, 1.0); /* the Emission pass: what the surface emits */
#endif
#if WORLD_RATIO_OUT == 1
  /* The SH light by lobe that the colour carries, and the ratio's sums. */
  out_world_diffuse = vec4(0.0, 0.0, 0.0, 1.0);
  out_world_specular = vec4(0.0, 0.0, 0.0, 1.0);
  out_world_sums = vec4(0.0);
#  if WORLD_RATIO
  if (world) {
    out_world_diffuse = vec4(world_d, 1.0);
    out_world_specular = vec4(world_s, 1.0);
    out_world_sums = world_sums;
  }
#  endif
#elif WORLD_RATIO_OUT == 2
  /* Blended over the surface behind: its unshadowed world light is seen through 1 - alpha. */
  out_world_diffuse = vec4(0.0, 0.0, 0.0, color.a);
  out_world_specular = vec4(0.0, 0.0, 0.0, color.a);
#endif
#if COUNT_SHADED
  out_shaded = 1.0; /* this pixel was shaded in this sample (programs.LIT_COLOR_COUNTED) */
#endif
}

#endif /* PENUMBRA_LIB_LIT_OUTPUTS */
