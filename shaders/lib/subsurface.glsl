// requires: lib/lit_surface.glsl lib/shadow_filters.glsl lib/burley.glsl
#ifndef PENUMBRA_LIB_SUBSURFACE
#define PENUMBRA_LIB_SUBSURFACE

/* What the subsurface draw adds and writes besides the light below the surface (features/subsurface.py,
 * LIGHT_PASS_SUBSURFACE): that light is the diffuse share below (Subsurface Weight) lit as a
 * diffuse surface, under any sheen and coat; the diffusion divides it by
 *   out_sss_albedo  rgb: that share's albedo x what the layers over it keep, a: view depth
 * to have the light entering each point, spreads that over the Burley profile of
 *   out_sss_radius  rgb: Burley's d per channel (world units), a: 1 (a subsurface pixel)
 * and multiplies it by the albedo where it leaves (shaders/subsurface.frag.glsl). */

#if LIGHT_PASS == LIGHT_PASS_SUBSURFACE
/* The surface's subsurface parameters (MaterialInputs.sss: Burley's d per channel, the share
 * below), set by surface_setup for the light passes' loops. */
vec4 lit_sss = vec4(0.0);

/* The share-weighted albedo of the lobes' diffuse below the surface, times what the layers
 * over it keep. */
vec3 subsurface_albedo(Surface s)
{
  vec3 albedo = vec3(0.0);
  for (int k = 0; k < NODE_LOBES; k++) {
    albedo += max(s.lobe[k].weight, 0.0) * max(s.lobe[k].albedo, vec3(0.0));
  }
#  if NODE_SHEEN
  albedo *= s.sheen.below;
#  endif
#  if NODE_COAT
  albedo *= s.coat.below;
#  endif
  return albedo;
}

/* Translucency (Jimenez et al. 2010, "Real-Time Realistic Skin Translucency"): light L arriving
 * from behind the surface (``to_light`` against its normal) through what its map holds in
 * front of P, that thickness crossed as Burley's profile lets it (burley_through per channel),
 * leaving here as diffuse light; per unit of the light's colour x irradiance. 0 without a map. */
vec3 subsurface_through(Surface s, LightData L, vec3 to_light)
{
  float back = -dot(s.Ng, to_light);
  if (back <= 0.0 || lit_sss.w <= 0.0) {
    return vec3(0.0);
  }
  float thickness = shadow_thickness(L, s.P);
  if (thickness < 0.0) {
    return vec3(0.0);
  }
  vec3 through = vec3(burley_through(lit_sss.r, thickness), burley_through(lit_sss.g, thickness),
                      burley_through(lit_sss.b, thickness));
  return through * back * subsurface_albedo(s) * (L.diffuse_factor / M_PI);
}

/* How much of that light leaves here towards the viewer, against a Lambertian surface: c0
 * (``exit``, node_sss_walk) towards the normal, c0 + 3 (1 - c0) (1 - cos) at the view's angle
 * (its cosine-weighted mean over the hemisphere is 1). Both the light and the albedo the draw
 * writes carry it, so the diffusion divides it out where the light enters and keeps it here. */
vec3 subsurface_exit(Surface s, vec3 exit)
{
  float mu = clamp(dot(s.lobe[0].N, s.V), 0.0, 1.0);
  return exit + 3.0 * (1.0 - exit) * (1.0 - mu);
}

void subsurface_outputs(Surface s, vec4 sss, vec3 exit)
{
#  if HOLDOUT
  /* A hole in the film (Object > Visibility > Holdout): not a subsurface pixel, nothing spreads
   * into it or out of it. */
  out_sss_albedo = vec4(0.0, 0.0, 0.0, v_view_depth);
  out_sss_radius = vec4(0.0);
#  else
  out_sss_albedo = vec4(subsurface_albedo(s) * exit, v_view_depth);
  out_sss_radius = vec4(max(sss.rgb, vec3(0.0)), 1.0);
#  endif
}
#endif

#endif /* PENUMBRA_LIB_SUBSURFACE */
