/* Forward lighting: Lambert diffuse + GGX (or normalised Blinn/Phong) specular; the world
 * lights every surface as ambient: diffuse from its spherical-harmonic irradiance, specular
 * (what makes metals look like metal) from its radiance around the reflected direction,
 * blurred by roughness and weighted by an analytic environment BRDF. Each light is attenuated
 * by its shadow visibility; back faces of a light (N.L <= 0) skip the shadow filter.
 * Emission adds after lighting and is never shadowed.
 *
 * The material comes from the MaterialData block and, per variant (engine/frame/programs.py
 * material_defines), image textures, a colour attribute, a normal map and the alpha mode.
 *
 * The lit pass pays only for what it uses: lights sampled over their extent come first
 * (frame.sampled_count, PCSS of their per-sample size), then the other lights with a shadow
 * map (up to frame.shadowed_count, the scene's filter), then lights without a map (no filter
 * code); a scene without lights runs no loop. With several
 * local lights, each pixel loops only over the lights its screen bin lists; with a few lights
 * and no bins, the counts are compiled in and each light is called by its constant index.
 *
 * Object > Shading > Shadow Terminator (engine/scene/terminator.py), per object variant:
 * TERMINATOR_OFFSET lifts each light's shadow point towards the smooth surface the vertex
 * normals imply (Cycles' Geometry Offset), TERMINATOR_NORMAL moves it along the normal (EEVEE's
 * Normal Offset), TERMINATOR_SHADING raises the cosine term's frequency (Cycles' Shading
 * Offset).
 *
 * NODE_LOBES == 2 (a compiled node tree whose Mix / Add Shader joins two surfaces,
 * engine/scene/nodetree.py): the surface is two lobes, each its own Principled parameters and
 * shading normal, weighted per pixel (shaders/nodes/shader.glsl). Each light's shadow is
 * looked up once, then both lobes' BSDFs are evaluated; the world lights both; the colour is
 * the lobes' light summed by their weights. The Shadow pass weights each light by the heavier
 * lobe's cosine, the Normal pass writes the heavier lobe's normal. Other materials compile
 * one lobe, as before.
 *
 * WORLD_AO (engine/frame/world_ao.py, lib/gtao.glsl): the world's diffuse light is scaled by its
 * visibility from screen-space ground-truth ambient occlusion over the camera depth prepass, its
 * specular by the specular occlusion that implies; lights and emission are untouched.
 *
 * DEBUG_LIT (the TEXEL_DENSITY, CASCADES and LIGHT_COST debug views, engine/frame/debug_view.py):
 * the pixel writes the lights it evaluated, the cascade it read and its worst texel density
 * instead of colour; with WORLD_AO (the WORLD_AO view) the world's visibility.
 *
 * SETTLE_TEST (engine/frame/settle.py, after a frame's pilot sample, lights at their centres):
 * the pixel writes whether any later sample could change it through a light (1 in red where
 * none can: every moving light's visibility is the same from all of the light,
 * lib/shadow_filters.glsl, and no facet turns across it; a dithered or blended surface never
 * settles) and, in green, how far the light it reflects is from its average over each
 * light's extent. */

#ifndef NODE_LOBES
#  define NODE_LOBES 1
#endif
#ifndef NODE_PROCEDURAL
#  define NODE_PROCEDURAL 0 /* a compiled node tree with procedural textures (programs.with_tree) */
#endif

struct Surface {
  vec3 P, N, V;
  vec3 Ng; /* the interpolated mesh normal, before any normal map: what shadow biases follow */
  vec3 Nf; /* the drawn facet's normal (the plane the shadow map holds), on Ng's side */
  vec3 Nv; /* the drawn facet's normal on the side it is seen from */
#if TERMINATOR_OFFSET
  vec3 smooth_offset; /* from the flat triangle to the smooth surface (world) */
#endif
  vec3 albedo;
  vec4 f0; /* rgb: reflectance at normal incidence, a: at grazing (Schlick's f90) */
  float shininess;
  float alpha; /* GGX roughness (Principled roughness squared) */
#if NODE_LOBES == 2
  /* The second lobe (N, albedo, f0, shininess, alpha above are the first), and the lobes'
   * weights. */
  vec3 N_b;
  vec3 albedo_b;
  vec4 f0_b;
  float shininess_b, alpha_b;
  vec2 w;
#endif
};

#define NO_SHADOW -1

/* WORLD_RATIO (a frame that samples the world's light with shadow-mapped directions and
 * lights surfaces with its SH light, frame/world_sampling.py): the world's light is U x S per
 * lobe (Heitz, Hill and McGuire 2018, "Combining Analytic Direct Illumination and Stochastic
 * Shadows"): U the SH light unshadowed (lobe_setup), diffuse U_d and specular U_s, S the ratio
 * of the directions' sums N of f cos V L / p and D of f cos L / p over the frame's samples,
 * f the lobe's BSDF, so a glossy lobe weighs its own shadow and its few bright directions do
 * not spot the diffuse light. The colour carries U whole; WORLD_RATIO_OUT 1 also writes U_d,
 * U_s and the sums (N_d, D_d, N_s, D_s), which the film accumulates with the colour's weights
 * and divides at resolve (lib/world_ratio.glsl): colour - U_d (1 - S_d) - U_s (1 - S_s), in
 * [colour - U, colour], never below zero. A sample with ambient occlusion adds its visibility
 * as one sample's worth of the sums. WORLD_RATIO_OUT 2 (blended surfaces) takes its own ratio
 * within the sample and writes what it leaves of the light behind it. */
#ifndef WORLD_RATIO
#  define WORLD_RATIO 0
#endif
#ifndef WORLD_RATIO_OUT
#  define WORLD_RATIO_OUT 0
#endif
#if WORLD_RATIO
vec4 world_sums = vec4(0.0); /* (N_d, D_d, N_s, D_s) of this sample's directions */
vec3 world_part_d = vec3(0.0), world_part_s = vec3(0.0); /* the last lobe_setup's U by lobe */
vec2 world_part_vis = vec2(1.0); /* and its ambient occlusion (diffuse, specular) */

/* One sample's worth of the sums from the last lobe_setup's ambient occlusion. */
vec4 world_ao_sums()
{
  float d = world_luminance(world_part_d), sp = world_luminance(world_part_s);
  return vec4(world_part_vis.x * d, d, world_part_vis.y * sp, sp);
}

/* A direction's (diffuse, specular) f cos L / p for one lobe, in luminance. */
vec2 world_direction_weights(vec3 E, vec3 albedo, vec3 f, float cosine, LightData L)
{
  vec3 fd = albedo / M_PI * L.diffuse_factor;
  return cosine * vec2(world_luminance(E * fd), world_luminance(E * max(f - fd, vec3(0.0))));
}
#endif

#if DEBUG_TERM
/* The WORLD_LIGHT (1) and INDIRECT (2) debug views: the one term of the colour they show. */
vec3 debug_term = vec3(0.0);
#endif

#if TERMINATOR_OFFSET
/* Cycles' smooth-surface offset at this fragment (engine/scene/terminator.py smooth_offset):
 * the interpolated normal times the height of the parabola through the triangle's vertex
 * normals, bounded by the vertices' tangent planes (affine over the triangle, interpolated
 * exactly from the corners). ``Nv``: the facet's normal towards the viewer; seen from
 * behind its normals the offset goes the other way. */
vec3 smooth_surface_offset(vec3 Nv)
{
  float u = v_tbary.x, v = v_tbary.y;
  float a = v_tabc.x, b = v_tabc.y, c = v_tabc.z;
  float h = a * u * (u - 1.0) + (a + b + c) * u * v + b * v * (v - 1.0);
  vec3 n = v_tnormal;
  if (dot(n, Nv) > 0.0) {
    vec3 e = max(v_tfront, vec3(0.0));
    h = max(min(min(e.x, e.y), e.z), 0.5 * h);
  }
  else {
    vec3 e = max(v_tback, vec3(0.0));
    h = min(-min(min(e.x, e.y), e.z), 0.5 * h);
  }
  vec3 o = n * h;
  return (any(isnan(o)) || any(isinf(o))) ? vec3(0.0) : o;
}

/* How much of the offset light direction L gets: all of it where the smooth normal (NL) and
 * the facet (NgL) are at a grazing angle to it, none beyond the Geometry Offset. */
float smooth_offset_amount(float NL, float NgL)
{
  float cutoff = terminator_geometry_offset;
  return (NL < cutoff) ? clamp(2.0 - (NgL + NL) / cutoff, 0.0, 1.0) : clamp(1.0 - NgL / cutoff, 0.0, 1.0);
}
#endif

/* The cosine term; Cycles' Shading Offset replaces cos(theta) by max(cos(f theta), 0). */
float cosine_term(float NdotL)
{
#if TERMINATOR_SHADING
  return max(cos(acos(min(NdotL, 1.0)) * terminator_shading_frequency), 0.0);
#else
  return NdotL;
#endif
}

/* The Principled specular's Fresnel between f0 and 1: the exact dielectric Fresnel of IOR 1.5
 * remapped from its F0 (0.04) to 1, as Cycles' generalized Schlick Fresnel with a negative
 * exponent (bsdf_microfacet.h) gives it; Schlick's (1 - cos)^5 falls short of it by up to a
 * third between 40 and 80 degrees. ``c``: the cosine between the light and the half vector. */
float fresnel_shape(float c)
{
  c = clamp(c, 0.0, 1.0);
  float g = sqrt(1.25 + c * c); /* eta^2 - 1 + c^2 at eta = 1.5 */
  float a = (g - c) / (g + c);
  float b = (c * (g + c) - 1.0) / (c * (g - c) + 1.0);
  return (0.5 * a * a * (1.0 + b * b) - 0.04) / 0.96;
}

/* One lobe's BSDF for light from ``to_light`` (N.L > 0): its diffuse and specular parts, each
 * scaled by the light's factors. */
vec3 lobe_brdf(vec3 N, vec3 V, vec3 albedo, vec4 f0, float shininess, float alpha, vec3 to_light, float NdotL,
               LightData L)
{
#if SPECULAR_MODEL == SPECULAR_GGX
  vec3 H = normalize(to_light + V);
  float NdotH = max(dot(N, H), 0.0);
  float NdotV = max(dot(N, V), 1e-4);
  float a2 = alpha * alpha;
  float dd = NdotH * NdotH * (a2 - 1.0) + 1.0;
  float D = a2 / (M_PI * dd * dd);
  /* Height-correlated Smith visibility G / (4 N.L N.V). */
  float gv = NdotL * sqrt(NdotV * NdotV * (1.0 - a2) + a2);
  float gl = NdotV * sqrt(NdotL * NdotL * (1.0 - a2) + a2);
  float Vis = 0.5 / max(gv + gl, 1e-8);
  /* Fresnel from f0.rgb towards f90 (f0.a: lobe_setup) along the exact dielectric curve
   * (fresnel_shape). */
  float fw = fresnel_shape(dot(to_light, H));
  vec3 spec = (f0.rgb + (f0.a - f0.rgb) * fw) * (D * Vis);
  return albedo / M_PI * L.diffuse_factor + spec * L.specular_factor;
#else
#  if SPECULAR_MODEL == SPECULAR_BLINN
  vec3 H = normalize(to_light + V);
  float spec = (shininess + 8.0) / (8.0 * M_PI) * pow(max(dot(N, H), 0.0), shininess);
#  else
  vec3 R = reflect(-to_light, N);
  float spec = (shininess + 2.0) / (2.0 * M_PI) * pow(max(dot(R, V), 0.0), shininess);
#  endif
  return albedo / M_PI * L.diffuse_factor + f0.rgb * spec * L.specular_factor;
#endif
}

#if SETTLE_TEST
bool settle_unstable = false;
float settle_spread = 0.0;

/* The light L reflects towards the viewer from ``to_light`` delivering ``irradiance``,
 * unshadowed (both lobes with NODE_LOBES == 2). */
vec3 reflected_light(LightData L, Surface s, vec3 to_light, float irradiance)
{
  vec3 r = vec3(0.0);
  float NdotL = dot(s.N, to_light);
#  if NODE_LOBES == 2
  if (NdotL > 0.0) {
    r += (s.w.x * cosine_term(NdotL)) * lobe_brdf(s.N, s.V, s.albedo, s.f0, s.shininess, s.alpha, to_light, NdotL, L);
  }
  float NdotL_b = dot(s.N_b, to_light);
  if (NdotL_b > 0.0) {
    r += (s.w.y * cosine_term(NdotL_b)) *
         lobe_brdf(s.N_b, s.V, s.albedo_b, s.f0_b, s.shininess_b, s.alpha_b, to_light, NdotL_b, L);
  }
#  else
  if (NdotL > 0.0) {
    r += cosine_term(NdotL) * lobe_brdf(s.N, s.V, s.albedo, s.f0, s.shininess, s.alpha, to_light, NdotL, L);
  }
#  endif
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
 * Shadow pass counts the light wherever it arrives. */
void settle_unreached(LightData L, Surface s, vec3 to_light, float irradiance, const int filter_id)
{
  if (!settle_light(L, s, to_light, irradiance, dot(s.Ng, to_light)) || filter_id == NO_SHADOW) {
    return;
  }
  float NgdotL = dot(s.Ng, to_light);
  float v = (NgdotL <= 0.0) ? 0.0 : shadow_visibility(L, s.P, s.Ng, s.Nf, NgdotL, dot(s.Nf, to_light), filter_id);
  if (v != 1.0) {
    settle_unstable = true;
  }
}
#endif

/* Add light i's contribution. ``filter_id`` is a literal at each call (FILTER_* or NO_SHADOW), so
 * the compiler keeps a shadow filter only where a light has a map, and only that one. */
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
  float NdotL = dot(s.N, to_light);
#if NODE_LOBES == 2
  float NdotL_b = dot(s.N_b, to_light);
  if ((NdotL <= 0.0 && NdotL_b <= 0.0) || irradiance <= 0.0) {
#  if SETTLE_TEST
    if (filter_id == FILTER_PCSS || filter_id == NO_SHADOW) {
      settle_unreached(L, s, to_light, irradiance, filter_id); /* other points may reach it */
    }
#  endif
    return;
  }
  float cosine_a = (NdotL > 0.0) ? cosine_term(NdotL) : 0.0;
  float cosine_b = (NdotL_b > 0.0) ? cosine_term(NdotL_b) : 0.0;
  float cosine = (s.w.y > s.w.x) ? cosine_b : cosine_a; /* the Shadow pass's: the heavier lobe's */
#else
  if (NdotL <= 0.0 || irradiance <= 0.0) {
#  if SETTLE_TEST
    if (filter_id == FILTER_PCSS || filter_id == NO_SHADOW) {
      settle_unreached(L, s, to_light, irradiance, filter_id); /* other points may reach it */
    }
#  endif
    return;
  }
  float cosine = cosine_term(NdotL);
#endif
  /* Shadow pass: direct light that arrives over direct light that would arrive unshadowed,
   * each light weighted by the luminance of its irradiance here (1 where no light reaches). */
  float weight = dot(L.color, vec3(0.2126, 0.7152, 0.0722)) * irradiance * cosine;
  float NgdotL = dot(s.Ng, to_light);
  vec3 shadow_P = s.P;
#if TERMINATOR_OFFSET
  shadow_P += s.smooth_offset * smooth_offset_amount(NgdotL, dot(s.Nv, to_light));
#endif
#if TERMINATOR_NORMAL
  /* EEVEE: along the normal, by Normal Offset x saturate(1 - N.L / Geometry Offset). */
  shadow_P += s.Ng * (clamp(1.0 - NgdotL / terminator_geometry_offset, 0.0, 1.0) * terminator_normal_offset);
#endif
  /* On a closed surface seen from outside, a facet turned away from the light (its own plane,
   * not the smoothed normal) is in the surface's own shadow: the ray to the light enters the
   * solid. Decided exactly, with no bias, where the map's depths are nearly equal (lights
   * with jittered maps, whose biases shrink with the samples; one-sample frames as before).
   * Not where Shadow Terminator's Geometry Offset moves the point off its facet: the map
   * decides there, as Cycles' offset ray does. */
#if TERMINATOR_OFFSET
  bool turned = false;
#else
  bool turned = solid != 0 && L.jittered != 0 && dot(s.Nf, to_light) <= 0.0;
#endif
  float visibility = (filter_id == NO_SHADOW) ? 1.0 :
                     (NgdotL <= 0.0 || turned) ? 0.0 :
                                                 shadow_visibility(L, shadow_P, s.Ng, s.Nf, NgdotL, dot(s.Nf, to_light), filter_id);
#if SETTLE_TEST
  /* Lights that move between samples are the sampled ones (FILTER_PCSS) and, without a map,
   * any with an extent; the scene's filter serves lights that stay put. */
  if (visibility < 0.0) {
    settle_unstable = true;
    visibility = 1.0;
  }
  if (visibility > 0.0 && (filter_id == FILTER_PCSS || filter_id == NO_SHADOW)) {
    settle_light(L, s, to_light, irradiance, NgdotL);
  }
#endif
#if WORLD_RATIO
  if (L.world != 0) {
    /* A direction of the world's light adds to the ratio's sums (WORLD_RATIO above), by
     * lobe: diffuse and specular, each weighted by its own f cos L / p. */
    vec3 E = L.color * irradiance;
    vec2 w = vec2(0.0);
#  if NODE_LOBES == 2
    if (NdotL > 0.0) {
      vec3 f = lobe_brdf(s.N, s.V, s.albedo, s.f0, s.shininess, s.alpha, to_light, NdotL, L);
      w += s.w.x * world_direction_weights(E, s.albedo, f, cosine_a, L);
    }
    if (NdotL_b > 0.0) {
      vec3 f = lobe_brdf(s.N_b, s.V, s.albedo_b, s.f0_b, s.shininess_b, s.alpha_b, to_light, NdotL_b, L);
      w += s.w.y * world_direction_weights(E, s.albedo_b, f, cosine_b, L);
    }
#  else
    vec3 f = lobe_brdf(s.N, s.V, s.albedo, s.f0, s.shininess, s.alpha, to_light, NdotL, L);
    w = world_direction_weights(E, s.albedo, f, cosine, L);
#  endif
    w = max(w, vec2(0.0));
    world_sums += vec4(visibility * w.x, w.x, visibility * w.y, w.y);
    return;
  }
#endif
#if WORLD_LIGHTS
  /* A direction of the world's light carrying its whole light (with light portals: the SH
   * light is then not given, frame/world_sampling.py); not part of the Shadow pass (the
   * lights' alone, as Cycles'). */
  float world_light = float(L.world);
#else
  const float world_light = 0.0;
#endif
  unshadowed += weight * (1.0 - world_light);
  arriving += weight * visibility * (1.0 - world_light);
#if NODE_LOBES == 2
  /* Both lobes under the one shadow lookup, summed by their weights. */
  vec3 reflected = vec3(0.0);
  if (NdotL > 0.0) {
    reflected += (s.w.x * cosine_a) * lobe_brdf(s.N, s.V, s.albedo, s.f0, s.shininess, s.alpha, to_light, NdotL, L);
  }
  if (NdotL_b > 0.0) {
    reflected += (s.w.y * cosine_b) *
                 lobe_brdf(s.N_b, s.V, s.albedo_b, s.f0_b, s.shininess_b, s.alpha_b, to_light, NdotL_b, L);
  }
  vec3 added = (L.color * visibility) * irradiance * reflected;
#else
  vec3 E = (L.color * visibility) * (irradiance * cosine);
  vec3 added = E * lobe_brdf(s.N, s.V, s.albedo, s.f0, s.shininess, s.alpha, to_light, NdotL, L);
#endif
  color += added;
#if DEBUG_TERM == 1
  debug_term += world_light * added;
#endif
}

/* The world's radiance around direction d from its SH coefficients, each band scaled by
 * g.x (band 1) and g.y (band 2): (1, 1) is the radiance itself, (2/3, 1/4) the cosine-lobe
 * convolution (irradiance / pi). */
vec3 world_sh(vec3 d, vec2 g)
{
  vec3 r = frame.world_color;
  r += g.x * 0.4886025 * (frame.world_sh1.xyz * d.y + frame.world_sh2.xyz * d.z + frame.world_sh3.xyz * d.x);
  r += g.y * (1.0925484 * (frame.world_sh4.xyz * d.x * d.y + frame.world_sh5.xyz * d.y * d.z +
                           frame.world_sh7.xyz * d.x * d.z) +
              0.3153916 * frame.world_sh6.xyz * (3.0 * d.z * d.z - 1.0) +
              0.5462742 * frame.world_sh8.xyz * (d.x * d.x - d.y * d.y));
  return max(r, vec3(0.0));
}

/* The specular lobe's directional albedo as a scale and bias of f0 (the split sum's
 * environment BRDF): f0 a + b is what the lobe reflects of light from all directions, the
 * energy the diffuse layer below does not get and the weight of the world's specular. (E, S)
 * come from lib/ggx_albedo.glsl (GGX, height-correlated Smith, the Fresnel curve of
 * fresnel_shape). Multiple scattering between the microfacets adds 1 + F_ms (1 - E) / E (Kulla
 * and Conty 2017, as Cycles' microfacet_ggx_preserve_energy: F_ms = F_ss E_avg / (1 - F_ss
 * (1 - E_avg)), F_ss the Fresnel's cosine-weighted mean), for ``f`` the lobe's mean f0. The
 * bias (the Fresnel rim) is scaled by ``f90``: a surface without specular has none. */
vec2 env_brdf(float f, float f90, float rough, float NdotV)
{
  vec2 es = ggx_albedo(rough, NdotV);
  float e_avg = ggx_albedo_avg(rough);
  float f_ss = f + (1.0 - f) * GGX_S_AVG * f90;
  float f_ms = f_ss * e_avg / (1.0 - f_ss * (1.0 - e_avg));
  float ms = 1.0 + f_ms * (1.0 - es.x) / max(es.x, 1e-4);
  return vec2(es.x - es.y, es.y * f90) * ms;
}

#if WORLD_AO
/* The world's cosine-weighted visibility at the normal of the lobe being set up (lib/gtao.glsl,
 * set in main before each lobe_setup). */
float world_visibility = 1.0;
#endif

/* Light from the world: diffuse irradiance, and specular radiance around the reflected
 * direction, wider with roughness, weighted by the environment BRDF ``ab``. With WORLD_AO the
 * diffuse is scaled by the world's visibility and the specular by the specular occlusion it
 * implies for this lobe (gtao_specular). */
vec3 world_light(vec3 N, vec3 V, vec3 albedo, vec3 f0, float rough, vec2 ab)
{
  vec3 diffuse = albedo * world_sh(N, vec2(2.0 / 3.0, 0.25));
  vec3 R = reflect(-V, N);
  float t = rough * rough;
  vec3 radiance = world_sh(R, vec2(mix(1.0, 2.0 / 3.0, t), mix(1.0, 0.25, t)));
  vec3 specular = radiance * (f0 * ab.x + ab.y);
#if WORLD_AO && WORLD_RATIO
  /* The occlusion goes into the ratio's sums (main), the colour keeps U whole. */
  world_part_vis = vec2(world_visibility, gtao_specular(world_visibility, max(dot(N, V), 0.0), t));
#elif WORLD_AO
  diffuse *= world_visibility;
  specular *= gtao_specular(world_visibility, max(dot(N, V), 0.0), t);
#endif
#if WORLD_RATIO
  world_part_d = diffuse;
  world_part_s = specular;
#endif
  return diffuse + specular;
}

/* One lobe's shading values from its Principled parameters (``albedo`` with the specular
 * layer's energy taken out), and the light the world gives it. */
vec3 lobe_setup(vec3 base, float rough, float metal, vec4 spec, vec3 N, vec3 V, out vec3 albedo, out vec4 f0,
                out float shininess, out float alpha)
{
  rough = clamp(rough, 0.0, 1.0);
  /* The dielectric's F0 (rgb, tinted) and untinted f0 (a): from IOR, Specular IOR Level and
   * Specular Tint (node_principled_f0; materials.dielectric_f0 for a read material). */
  spec = max(spec, vec4(0.0));
  metal = clamp(metal, 0.0, 1.0);
  albedo = base * (1.0 - metal);
  /* Schlick's f90: 1, but a surface without specular (f0 ~ 0) has no Fresnel rim either, as
   * the Principled BSDF at IOR 1 or Specular IOR Level 0 (the tint does not change it: F90 is
   * white in Blender's generalized Schlick). */
  float f90 = clamp(50.0 * mix(spec.a, dot(base, vec3(0.3333)), metal), 0.0, 1.0);
  f0 = vec4(mix(spec.rgb, base, metal), f90);
  float a = max(rough * rough, 0.02);
  shininess = 2.0 / (a * a) - 2.0;
  alpha = max(rough * rough, 0.002);

  /* Energy: light reflected by the specular layer does not reach the diffuse one below (the
   * Principled BSDF's layering), estimated per pixel from the directional albedo. */
  float NdotV = max(dot(N, V), 1e-4);
  vec2 ab = env_brdf(dot(f0.rgb, vec3(0.3333)), f90, rough, NdotV);
  /* Metallic mixes a metal and a dielectric; only the dielectric's own specular sits over its
   * diffuse, per channel (a tinted specular takes its own colour out of the diffuse). */
  vec2 ab_dielectric = env_brdf(dot(spec.rgb, vec3(0.3333)), clamp(50.0 * spec.a, 0.0, 1.0), rough, NdotV);
  albedo *= clamp(1.0 - (spec.rgb * ab_dielectric.x + ab_dielectric.y), 0.0, 1.0);
  return world_light(N, V, albedo, f0.rgb, rough, ab);
}

void main()
{
  /* --- the material --- */
  vec4 base = material.base_color;
  float rough = material.roughness;
  float metal = material.metallic;
  float coverage = material.alpha;
  vec3 emission = material.emission;
  vec4 spec_f0 = material.specular; /* the dielectric's F0 (lobe_setup) */
  vec3 tree_normal = vec3(0.0); /* the tree's shading normal (NODE_NORMAL) */
#if NODE_LOBES == 2
  /* The second lobe's parameters and the lobes' weights (shaders/nodes/shader.glsl). */
  vec4 base_b = base;
  float rough_b = rough, metal_b = metal;
  vec4 spec_f0_b = spec_f0;
  vec3 tree_normal_b = vec3(0.0);
  vec2 lobe_weights = vec2(1.0, 0.0);
#endif
#if NODE_TREE
  {
    /* The material's compiled node tree (engine/scene/nodetree.py) gives every parameter. */
    vec3 V = (frame.is_ortho != 0) ? -frame.camera_forward : normalize(frame.camera_position - v_world);
    vec3 Nt = v_normal;
    float l = length(Nt);
    Nt = (l > 1e-20) ? Nt / l : vec3(0.0, 0.0, 1.0);
    bool front = dot(Nt, V) >= 0.0;
#  if NODE_LOBES == 2
    node_closure_resolve_lobes(node_tree_closure(front ? Nt : -Nt, V, front), base, rough, metal, spec_f0,
                               coverage, emission, tree_normal, base_b, rough_b, metal_b, spec_f0_b, tree_normal_b,
                               lobe_weights);
#  else
    node_tree(front ? Nt : -Nt, V, front, base, rough, metal, spec_f0, coverage, emission, tree_normal);
#  endif
  }
#endif
#if TEX_BASE_COLOR
  base *= SAMPLE_COLOR(base_color, v_uv);
#endif
#if HAS_VCOL && !NODE_TREE
  base *= v_color;
#endif
#if TEX_ROUGHNESS
  rough *= SAMPLE_VALUE(roughness, v_uv);
#endif
#if TEX_METALLIC
  metal *= SAMPLE_VALUE(metallic, v_uv);
#endif
#if TEX_ALPHA
  coverage *= SAMPLE_VALUE(alpha, v_uv);
#endif
#if TEX_EMISSION
  emission *= SAMPLE_COLOR(emission, v_uv).rgb;
#endif
#if ALPHA_MODE == 1 && SETTLE_TEST
  if (coverage <= 0.0) {
    discard; /* never drawn; where it covers some samples, it marks the pixel unsettled */
  }
#elif ALPHA_MODE == 1
  /* Hashed (EEVEE's Dithered): the surface covers a pixel in a fraction alpha of the samples
   * (stratified over the frame's samples by frame.alpha_offset). */
  if (coverage <= fract(pixel_hash(gl_FragCoord.xy) + frame.alpha_offset)) {
    discard;
  }
#elif ALPHA_MODE == 2
  if (coverage <= 0.0) {
    discard;
  }
#endif
#if EMISSION_ONLY
  /* The Emission pass drawn apart, over the z-buffer the lit pass left (a frame whose other
   * targets leave its own no room: lit_pass.py). */
#  if HOLDOUT
  out_color = vec4(0.0);
#  else
  out_color = vec4(emission, 1.0);
#  endif
  return;
#endif

  Surface s;
  s.P = v_world;
  vec3 N = v_normal;
  float nlen = length(N);
  if (!(nlen > 1e-20)) {
    /* Degenerate normal (zero-scale or broken mesh): fall back to the face normal. */
    N = cross(dFdx(s.P), dFdy(s.P));
    nlen = length(N);
  }
  N = (nlen > 1e-30) ? N / nlen : vec3(0.0, 0.0, 1.0);
#if HAIR_STRIP
  {
    /* Hair shaded as a cylinder, as EEVEE does: the normal turns from the camera (the strip's
     * centre) to the binormal (its edges); a pixel-wide strand (hair_pixel > 0) takes a random
     * point across it in each sample (EEVEE's random cosine distribution). */
    float cos_theta = clamp(v_hair.w, -1.0, 1.0);
    if (hair_pixel > 0.0) {
      cos_theta = 2.0 * fract(pixel_hash(gl_FragCoord.xy + 17.0) + frame.alpha_offset) - 1.0;
    }
    float sin_theta = sqrt(max(0.0, 1.0 - cos_theta * cos_theta));
    vec3 B = v_hair.xyz;
    float bl = length(B);
    N = normalize(N * sin_theta + ((bl > 1e-20) ? B / bl : vec3(0.0)) * cos_theta + 1e-30);
  }
#endif

  s.V = (frame.is_ortho != 0) ? -frame.camera_forward : normalize(frame.camera_position - s.P);
  s.Ng = (dot(N, s.V) < 0.0) ? -N : N;
  {
    /* Derivatives within the pixel quad come from this triangle: its plane. */
    vec3 f = cross(dFdx(s.P), dFdy(s.P));
    float fl = length(f);
    s.Nf = (fl > 1e-30) ? f / fl : s.Ng;
    s.Nv = (dot(s.Nf, s.V) < 0.0) ? -s.Nf : s.Nf;
    s.Nf = (dot(s.Nf, s.Ng) < 0.0) ? -s.Nf : s.Nf;
  }
#if TERMINATOR_OFFSET
  s.smooth_offset = smooth_surface_offset(s.Nv);
#endif
#if NODE_NORMAL
  N = (dot(tree_normal, tree_normal) > 0.0) ? normalize(tree_normal) : N; /* a Bump, ... */
#endif
#if TEX_NORMAL
  {
    /* Tangent-space normal map (Blender's Normal Map node): MikkTSpace tangent and sign from
     * the mesh, or a frame from screen-space derivatives of the UVs where it has none. */
    vec3 mapped = SAMPLE_COLOR(normal, v_uv).rgb * 2.0 - 1.0;
    vec3 T = v_tangent.xyz;
    float sign_b = v_tangent.w;
    if (sign_b == 0.0 || !(dot(T, T) > 1e-20)) {
      vec3 dp1 = dFdx(s.P), dp2 = dFdy(s.P);
      vec2 du1 = dFdx(v_uv), du2 = dFdy(v_uv);
      vec3 dp2perp = cross(dp2, N), dp1perp = cross(N, dp1);
      T = dp2perp * du1.x + dp1perp * du2.x;
      vec3 B = dp2perp * du1.y + dp1perp * du2.y;
      sign_b = (dot(cross(N, T), B) < 0.0) ? -1.0 : 1.0;
    }
    T = T - N * dot(N, T);
    float tl = length(T);
    if (tl > 1e-20) {
      T /= tl;
      vec3 B = sign_b * cross(N, T);
      vec3 perturbed = normalize(T * mapped.x + B * mapped.y + N * mapped.z);
      N = normalize(mix(N, perturbed, max(material.normal_strength, 0.0)));
    }
  }
#endif
  if (dot(N, s.V) < 0.0) {
    N = -N; /* two-sided, as Blender draws meshes */
  }
  s.N = N;
#if WORLD_AO
  /* The world's visibility from the camera depth prepass (lib/gtao.glsl): horizons marched
   * once, integrated for each lobe's normal. */
  mat3 ao_rotation = mat3(frame.view);
  GtaoHorizons ao_horizons = gtao_horizons((frame.view * vec4(s.P, 1.0)).xyz, gl_FragCoord.xy);
  world_visibility = gtao_visibility(ao_horizons, normalize(ao_rotation * s.N));
  float debug_world_ao = world_visibility;
#endif
  vec3 color = lobe_setup(base.rgb, rough, metal, spec_f0, s.N, s.V, s.albedo, s.f0, s.shininess, s.alpha);
#if WORLD_RATIO
  vec3 world_d = world_part_d, world_s = world_part_s; /* U by lobe (both lobes' summed) */
#  if WORLD_AO
  vec4 ao_sums = world_ao_sums();
#  endif
#endif
#if NODE_LOBES == 2
  /* The second lobe: its own normal where the tree gives one, else the first lobe's. */
#  if NODE_NORMAL
  vec3 N_b = (dot(tree_normal_b, tree_normal_b) > 0.0) ? normalize(tree_normal_b) : N;
#  else
  vec3 N_b = N;
#  endif
  s.N_b = (dot(N_b, s.V) < 0.0) ? -N_b : N_b;
#  if WORLD_AO
  world_visibility = gtao_visibility(ao_horizons, normalize(ao_rotation * s.N_b));
  debug_world_ao = dot(lobe_weights, vec2(debug_world_ao, world_visibility));
#  endif
  vec3 color_b = lobe_setup(base_b.rgb, rough_b, metal_b, spec_f0_b, s.N_b, s.V, s.albedo_b, s.f0_b, s.shininess_b,
                            s.alpha_b);
  s.w = lobe_weights;
  color = lobe_weights.x * color + lobe_weights.y * color_b;
#  if WORLD_RATIO
  world_d = lobe_weights.x * world_d + lobe_weights.y * world_part_d;
  world_s = lobe_weights.x * world_s + lobe_weights.y * world_part_s;
#    if WORLD_AO
  ao_sums = lobe_weights.x * ao_sums + lobe_weights.y * world_ao_sums();
#    endif
#  endif
#endif
  float arriving = 0.0, unshadowed = 0.0;
#if WORLD_RATIO && WORLD_AO
  /* A sample with ambient occlusion: its visibility is one sample's worth of the sums. */
  world_sums += ao_sums;
#endif
#if DEBUG_TERM == 1
  debug_term += color; /* the world's SH light (with its ambient occlusion) */
#endif
#if SETTLE_TEST && WORLD_LIGHTS
  vec3 world_term = color; /* the world's light, unshadowed (lobe_setup) */
#endif
#if DEBUG_LIT
  debug_dPdx = dFdx(s.P);
  debug_dPdy = dFdy(s.P);
#endif
#if LIGHT_BINS
  /* Only the lights this pixel's screen bin lists (engine/shadows/light_bins.py): word w of the bin
   * holds lights w * LIGHT_WORD_BITS + bit, as exact small integers in a float channel.
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
  /* The light counts are compiled in (frame/programs.py UNROLLED_LIGHTS): one call per light, each
   * reading its LightData at a constant offset; the counts fold each call to its filter. */
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
#if INDIRECT_RSM && !SETTLE_TEST && !DEBUG_LIT
  {
    /* One diffuse bounce from the lights' reflective shadow maps (lib/indirect_rsm.glsl),
     * reflected by the diffuse lobe(s). */
    vec3 bounced = indirect_rsm(s.P, s.N, v_view_depth) / M_PI;
#  if NODE_LOBES == 2
    bounced *= s.w.x * s.albedo + s.w.y * s.albedo_b;
#  else
    bounced *= s.albedo;
#  endif
    color += bounced;
#  if DEBUG_TERM == 2
    debug_term += bounced;
#  endif
  }
#endif
#if WORLD_RATIO && WORLD_RATIO_OUT != 1
  /* No film sums for this surface (a blended one): its own ratio within this sample. */
  color = world_ratio_apply(vec4(color, 1.0), world_d, world_s, world_sums).rgb;
#  if DEBUG_TERM == 1
  debug_term = world_ratio_apply(vec4(debug_term, 1.0), world_d, world_s, world_sums).rgb;
#  endif
#endif
  color += emission;
#if HOLDOUT
  out_color = vec4(0.0); /* Object > Visibility > Holdout: a hole in the film */
#elif ALPHA_MODE == 2
  float a = clamp(coverage, 0.0, 1.0);
  out_color = vec4(color * a, a); /* premultiplied, blended over what is behind */
#else
  out_color = vec4(color, 1.0);
#endif
#if DEBUG_TERM && !HOLDOUT
  out_color = vec4(debug_term, 1.0); /* the WORLD_LIGHT or INDIRECT debug view */
#endif
#if DEBUG_LIT && WORLD_AO
  out_color = vec4(debug_world_ao, 0.0, 0.0, 1.0); /* the WORLD_AO debug view: the world's visibility */
#elif DEBUG_LIT
  out_color = vec4(debug_lights, debug_cascade, debug_density, 1.0); /* a lit debug view's values */
#endif
#if SETTLE_TEST
  bool settled = !settle_unstable;
#  if WORLD_LIGHTS
  /* The world's light is sampled with shadow maps in this frame: what blocks it differs with
   * every direction, and the pilot cannot tell. Its samples can change the pixel by at most
   * the world's whole unshadowed light here (all of it blocked), which the settle test
   * weighs against the threshold like any light's spread: a dim world under bright lights
   * still settles, a world that lights the pixel keeps it sampling. */
  settle_spread += dot(max(world_term, vec3(0.0)), vec3(1.0));
#  endif
#  if INDIRECT_RSM
  settled = false; /* the bounce is sampled anew in every sample */
#  endif
#  if NODE_PROCEDURAL
  /* Procedural textures are evaluated at each sample's point, unfiltered: one sample cannot
   * tell their detail under the pixel (mortar lines between pixel centres), so they keep
   * sampling. Image textures are filtered (mipmaps) and settle. */
  settled = false;
#  endif
#  if ALPHA_MODE == 1 || ALPHA_MODE == 2
  settled = settled && coverage >= 1.0; /* what is behind shows in some samples */
#  endif
  out_color = vec4(settled ? 1.0 : 0.0, settle_spread, 0.0, 1.0);
#endif
#if AUX_OUTPUTS
  /* A ratio of weighted sums lies in [0, 1] but for rounding (a division need not be
   * correctly rounded: w / w may be 1.0000001). */
  out_shadow = (unshadowed > 0.0) ? clamp(arriving / unshadowed, 0.0, 1.0) : 1.0;
#  if NODE_LOBES == 2
  out_normal = vec4((s.w.y > s.w.x) ? s.N_b : N, v_view_depth); /* the heavier lobe's; w: the Depth pass */
#  else
  /* world-space shading normal, facing the camera (Normal pass); w: view depth (Depth pass) */
  out_normal = vec4(N, v_view_depth);
#  endif
#endif
#if EMISSION_OUTPUT
#  if HOLDOUT
  out_emission = vec4(0.0);
#  else
  out_emission = vec4(emission, 1.0); /* the Emission pass: what the surface emits */
#  endif
#endif
#if WORLD_RATIO_OUT == 1
  /* The SH light by lobe that the colour carries, and the ratio's sums (none in a hole, nor
   * in the INDIRECT view's image, which has no world light, nor in a lit debug view's). */
#  if HOLDOUT || DEBUG_TERM == 2 || DEBUG_LIT || !WORLD_RATIO
  out_world_diffuse = vec4(0.0, 0.0, 0.0, 1.0);
  out_world_specular = vec4(0.0, 0.0, 0.0, 1.0);
  out_world_sums = vec4(0.0);
#  else
  out_world_diffuse = vec4(world_d, 1.0);
  out_world_specular = vec4(world_s, 1.0);
  out_world_sums = world_sums;
#  endif
#elif WORLD_RATIO_OUT == 2
  /* Blended over the surface behind: its unshadowed world light is seen through 1 - alpha. */
  out_world_diffuse = vec4(0.0, 0.0, 0.0, out_color.a);
  out_world_specular = vec4(0.0, 0.0, 0.0, out_color.a);
#endif
#if COUNT_SHADED
  out_shaded = 1.0; /* this pixel was shaded in this sample (programs.LIT_COLOR_COUNTED) */
#endif
}
