// requires: lib/lights.glsl lib/shadow_filters.glsl lib/lit_surface.glsl lib/lit_terminator.glsl lib/lit_bsdf.glsl
#ifndef PENUMBRA_LIB_LIT_SETTLE
#define PENUMBRA_LIB_LIT_SETTLE

/* SETTLE_TEST (engine/frame/features/settling.py, after a frame's pilot sample, lights at their centres):
 * the pixel writes whether any later sample could change it through a light (1 in red where
 * none can: every moving light's visibility is the same from all of the light,
 * lib/shadow_filters.glsl, and no facet turns across it; a dithered or blended surface never
 * settles) and, in green, how far the light it reflects is from its average over each
 * light's extent. lit_lights.glsl add_light calls it for the lights that move. */

#if SETTLE_TEST
bool settle_unstable = false;
float settle_spread = 0.0;

/* The light L reflects towards the viewer from ``to_light`` delivering ``irradiance``,
 * unshadowed (every lobe, by its weight). */
vec3 reflected_light(LightData L, Surface s, vec3 to_light, float irradiance)
{
  vec3 r = vec3(0.0);
  for (int k = 0; k < NODE_LOBES; k++) {
    float NdotL = dot(s.lobe[k].N, to_light);
    if (NdotL > 0.0) {
      r += (s.lobe[k].weight * cosine_term(NdotL)) * lobe_brdf(s.lobe[k], s.V, to_light, NdotL, L);
    }
  }
  return L.color * irradiance * r;
}

/* How the light L reflects here differs from its average over the light's extent: the light
 * sits at its centre in this pass, so the first-order change cancels over the extent and
 * what remains is the curvature, from the light moved by its radius (a sun: tilted by its
 * half angle) both ways along two axes across ``to_light``: the mean of those four minus the
 * centre's, halved (a uniform disc's second moment is half theirs). A highlight narrower
 * than the light, or a light close to the surface, does not settle. Also whether a facet
 * turns across the light. */
bool settle_light(LightData L, Surface s, vec3 to_light, float irradiance, float NgdotL)
{
  bool sun = L.type == LIGHT_SUN;
  float extent = sun ? L.sun_tan_half_angle : L.shadow_radius;
  if (!(extent > 0.0)) {
    return false;
  }
  float angle = sun ? extent : extent / max(length(L.position - s.P), 1e-30);
  if (abs(NgdotL) < 1.5 * angle || abs(dot(s.Nf, to_light)) < 1.5 * angle) {
    settle_unstable = true; /* a facet (or the smooth normal) turns across the light */
    return true;
  }
  vec3 a = normalize(cross(to_light, (abs(to_light.z) < 0.9) ? vec3(0.0, 0.0, 1.0) : vec3(1.0, 0.0, 0.0)));
  vec3 b = cross(to_light, a);
  vec3 c0 = reflected_light(L, s, to_light, irradiance);
  vec3 mean = vec3(0.0);
  for (int k = 0; k < 4; k++) {
    vec3 o = (k == 0) ? a : (k == 1) ? -a : (k == 2) ? b : -b;
    vec3 l;
    float e;
    if (sun) {
      l = normalize(to_light + extent * o);
      e = 1.0;
    }
    else {
      LightData M = L;
      M.position = L.position + extent * o;
      light_incident(M, s.P, l, e);
    }
    mean += 0.25 * reflected_light(L, s, l, e);
  }
  settle_spread += 0.5 * dot(abs(mean - c0), vec3(1.0));
  return dot(mean, vec3(1.0)) > 0.0;
}

/* A light that does not reach P from its centre (outside a spot's cone, behind the surface)
 * but may from other points of it: the pixel settles only if those points see P, for the
 * Shadow pass counts the light wherever it arrives. Only lights that move between samples
 * (FILTER_PCSS, or without a map) can. */
void settle_unreached(LightData L, Surface s, vec3 to_light, float irradiance, const int filter_id)
{
  if (filter_id != FILTER_PCSS && filter_id != NO_SHADOW) {
    return;
  }
  if (!settle_light(L, s, to_light, irradiance, dot(s.Ng, to_light)) || filter_id == NO_SHADOW) {
    return;
  }
  float NgdotL = dot(s.Ng, to_light);
  float v = (NgdotL <= 0.0) ? 0.0 : shadow_visibility(L, s.P, s.Ng, s.Nf, NgdotL, dot(s.Nf, to_light), filter_id);
  if (v != 1.0) {
    settle_unstable = true;
  }
}

/* A light that reaches P: lights that move between samples are the sampled ones (FILTER_PCSS)
 * and, without a map, any with an extent; the scene's filter serves lights that stay put.
 * Returns the visibility to use (a visibility the filter could not decide, < 0, is 1 and
 * marks the pixel unsettled). */
float settle_reached(LightData L, Surface s, vec3 to_light, float irradiance, float NgdotL, float visibility,
                     const int filter_id)
{
  if (visibility < 0.0) {
    settle_unstable = true;
    visibility = 1.0;
  }
  if (visibility > 0.0 && (filter_id == FILTER_PCSS || filter_id == NO_SHADOW)) {
    settle_light(L, s, to_light, irradiance, NgdotL);
  }
  return visibility;
}

/* The pixel's settle flags (red: settled; green: the light's spread), from what the lights
 * found and what else may change between samples: the world's directions (WORLD_LIGHTS), whose
 * samples can change the pixel by at most the world's whole unshadowed light ``world_term``
 * here (all of it blocked): weighed against the threshold like any light's spread, so a dim
 * world under bright lights still settles and a world that lights the pixel keeps it
 * sampling; the bounce (sampled anew each sample); procedural textures (evaluated at each
 * sample's point, unfiltered: one sample cannot tell their detail under the pixel; image
 * textures are filtered and settle); what is behind a dithered or blended surface. */
vec4 settle_flags(vec3 world_term, float coverage)
{
  bool settled = !settle_unstable;
#  if WORLD_LIGHTS
  settle_spread += dot(max(world_term, vec3(0.0)), vec3(1.0));
#  endif
#  if INDIRECT_RSM || NODE_PROCEDURAL
  settled = false;
#  endif
#  if ALPHA_MODE == 1 || ALPHA_MODE == 2
  settled = settled && coverage >= 1.0;
#  endif
  /* Depth of field (engine/frame/lens.py): where the circle of confusion is wider than half a
   * pixel, every point of the lens sees this surface elsewhere. */
  if (frame.lens_coc.z != 0.0) {
    float z = max(v_view_depth, 1e-30);
    float spread = (frame.is_ortho != 0) ? abs(z * frame.lens_coc.y - 1.0) : abs(frame.lens_coc.y - 1.0 / z);
    settled = settled && 2.0 * frame.lens_coc.x * spread <= 0.5;
  }
  return vec4(settled ? 1.0 : 0.0, settle_spread, 0.0, 1.0);
}
#endif

#endif /* PENUMBRA_LIB_LIT_SETTLE */
