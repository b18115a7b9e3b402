// requires: lib/common.glsl lib/world_sh.glsl lib/volumes.glsl lib/lit_debug.glsl lib/gtao.glsl lib/world_ratio.glsl lib/lit_surface.glsl lib/lit_bsdf.glsl lib/material.glsl lib/world_env.glsl lib/ssr.glsl lib/planar.glsl lib/cubes.glsl lib/sheen.glsl lib/anisotropy.glsl
#ifndef PENUMBRA_LIB_LIT_WORLD
#define PENUMBRA_LIB_LIT_WORLD

/* The world's light on the surface (engine/frame/world/sh_light.py, world/directions.py, world/occlusion.py):
 * diffuse from its spherical-harmonic irradiance, specular (what makes metals look like metal)
 * from its radiance around the reflected direction, blurred by roughness and weighted by the
 * environment BRDF. WORLD_ENV (features/world_env.py): an Environment Texture's specular from
 * the image itself, prefiltered by roughness (lib/world_env.glsl), not from its SH. SSR
 * (lib/ssr.glsl, features/reflections.py): a lobe of roughness under WORLD_RATIO_ROUGH reflects
 * the scene where a traced ray meets it, the world's light where it meets nothing. PLANAR
 * (lib/planar.glsl, features/planar.py): in a Plane probe's influence the ray is traced through
 * the probe's mirrored capture first, and on the screen where that meets nothing; CUBES
 * (lib/cubes.glsl, features/cubes.py): what both leave, through a Sphere probe's cube map and
 * the camera's.
 *
 * WORLD_AO (lib/gtao.glsl): the world's diffuse light is scaled by its visibility from
 * screen-space ground-truth ambient occlusion over the camera depth prepass, its specular by the
 * specular occlusion that implies; lights and emission are untouched.
 *
 * WORLD_RATIO (a frame that samples the world's light with shadow-mapped directions and lights
 * surfaces with its SH light, frame/world/directions.py): the world's light is U x S per lobe
 * (Heitz, Hill and McGuire 2018, "Combining Analytic Direct Illumination and Stochastic
 * Shadows"): U the SH light unshadowed, diffuse U_d and specular U_s, S the ratio of the
 * directions' sums N of f cos V L / p and D of f cos L / p over the frame's samples, f the
 * lobe's BSDF, so a glossy lobe weighs its own shadow and its few bright directions do not spot
 * the diffuse light. The colour carries U whole; WORLD_RATIO_OUT 1 also writes U_d, U_s and the
 * sums (N_d, D_d, N_s, D_s), which the film accumulates with the colour's weights and divides at
 * resolve (lib/world_ratio.glsl): colour - U_d (1 - S_d) - U_s (1 - S_s), in [colour - U,
 * colour], never below zero. A sample with ambient occlusion adds its visibility as one
 * sample's worth of the sums. WORLD_RATIO_OUT 2 (blended surfaces) takes its own ratio within
 * the sample and writes what it leaves of the light behind it. */

#ifndef WORLD_RATIO
#  define WORLD_RATIO 0
#endif
#ifndef WORLD_RATIO_OUT
#  define WORLD_RATIO_OUT 0
#endif
#ifndef WORLD_ENV
#  define WORLD_ENV 0
#endif

/* The share of a lobe's specular world light that the world ratio's directions shadow: from 1
 * for a lobe of roughness WORLD_RATIO_ROUGH and more to 0 below WORLD_RATIO_SHARP. A few
 * directions a sample say nothing of a sharp lobe: each one's f cos L / p is 0 or huge, so the
 * ratio came out 0 or 1 from pixel to pixel, speckles that did not converge (a polished floor
 * by the feet of what stands on it, a mirror's black spots). The ratio leaves the sharp share
 * unshadowed: what hides the world from it is the scene a reflection would show, which the
 * traced rays (SSR) take. */
#define WORLD_RATIO_SHARP 0.2
#define WORLD_RATIO_ROUGH 0.5
#define SSR_FADE 0.4 /* lobes rougher than this fade out their traced rays (SSR) */
float world_ratio_share(float rough)
{
  return smoothstep(WORLD_RATIO_SHARP, WORLD_RATIO_ROUGH, rough);
}

#ifndef SSR_SETTLE
#  define SSR_SETTLE 0
#endif
vec3 world_point = vec3(0.0); /* the surface's point (surface_world_light), for the traced rays */
bool world_traced = false;    /* some lobe of this surface was (SSR) or would be (SSR_SETTLE) traced */
int world_lobe = 0;           /* the lobe world_light lights (its rays' random numbers) */

#if WORLD_RATIO
vec4 world_sums = vec4(0.0); /* (N_d, D_d, N_s, D_s) of this sample's directions */
vec3 world_d = vec3(0.0), world_s = vec3(0.0); /* U by lobe, the lobes' summed by weight */
vec3 world_part_d = vec3(0.0), world_part_s = vec3(0.0); /* the last world_light's U by lobe */
vec2 world_part_vis = vec2(1.0); /* and its ambient occlusion (diffuse, specular) */

/* One sample's worth of the sums from the last world_light's ambient occlusion. */
vec4 world_ao_sums()
{
  float d = world_luminance(world_part_d), sp = world_luminance(world_part_s);
  return vec4(world_part_vis.x * d, d, world_part_vis.y * sp, sp);
}

/* A direction's (diffuse, specular) f cos L / p for one lobe, in luminance; the specular's of
 * the share of it the ratio shadows (world_ratio_share of ``rough``). */
vec2 world_direction_weights(vec3 E, vec3 albedo, vec3 f, float cosine, LightData L, float rough)
{
  vec3 fd = albedo / M_PI * L.diffuse_factor;
  return cosine * vec2(world_luminance(E * fd), world_ratio_share(rough) * world_luminance(E * max(f - fd, vec3(0.0))));
}
#endif

#if WORLD_ENV
/* The image's radiance about direction ``R`` (world space) as a GGX lobe of Principled roughness
 * ``rough`` reflects it: between the image itself (roughness 0, read with the footprint of
 * ``R`` from pixel to pixel, as the background reads it) and the prefiltered levels, one each
 * WORLD_ENV_STEP of roughness (WORLD_ENV_LEVELS in world_env_atlas), linearly; times the
 * Background strength and clamped where the world's sun took the light above its threshold
 * (frame.env_params: strength, clamp or 0, premultiplied). */
const ivec3 world_env_levels[WORLD_ENV_COUNT] = ivec3[](WORLD_ENV_LEVELS);

vec3 world_env_radiance(vec3 R, float rough)
{
  vec3 d = mat3(frame.env_rotation_x.xyz, frame.env_rotation_y.xyz, frame.env_rotation_z.xyz) * R;
  vec2 uv = equirect_uv(d);
  float t = clamp(rough, 0.0, 1.0) / WORLD_ENV_STEP;
  int k = min(int(floor(t)), WORLD_ENV_COUNT);
  float f = t - float(k);
  /* The footprint's derivatives outside the branch: it depends on the lobe's roughness, and
   * derivatives in non-uniform control flow are undefined. */
  vec2 dx = dFdx(uv), dy = dFdy(uv);
  dx.x -= round(dx.x);
  dy.x -= round(dy.x);
  float width = length(d.xy);
  dx.x *= width;
  dy.x *= width;
  vec3 lo;
  if (k == 0) {
    lo = sample_image_grad(world_env_image, uv, dx, dy, ivec4(1, 0, 0, 0), frame.env_params.z > 0.5).rgb;
    lo = max(lo, vec3(0.0));
    if (frame.env_params.y > 0.0) {
      lo = min(lo, vec3(frame.env_params.y));
    }
  }
  else {
    lo = equirect_bilinear(world_env_atlas, world_env_levels[k - 1], uv).rgb;
  }
  vec3 r = lo;
  if (f > 0.0 && k < WORLD_ENV_COUNT) {
    r = mix(lo, equirect_bilinear(world_env_atlas, world_env_levels[k], uv).rgb, f);
  }
  return frame.env_params.x * max(r, vec3(0.0));
}
#endif

#if SSR || PLANAR || CUBES
/* A traced ray's further way of meeting the scene (a Plane probe's capture, the screen, the
 * cube maps, in that order) takes the share ``w`` of what the earlier ones left: the hits'
 * weight ``h`` and their weighted radiance ``hits`` grow by (1 - h) w and (1 - h) w ``seen``. */
void world_hit(float w, vec3 seen, inout float h, inout vec3 hits)
{
  float add = (1.0 - h) * w;
  hits += add * seen;
  h += add;
}
#endif

#if WORLD_AO
/* The world's cosine-weighted visibility at the normal of the lobe being lit
 * (surface_world_light). */
float world_visibility = 1.0;
#endif

/* Light from the world on lobe ``b``: diffuse irradiance, and specular radiance around the
 * lobe's dominant direction (specular_dominant), wider with roughness, weighted by the
 * environment BRDF ``ab``. With
 * WORLD_AO the diffuse is scaled by the world's visibility and the specular by the specular
 * occlusion it implies for this lobe (gtao_specular). */
/* The world's radiance about the reflected direction ``R`` as a glossy lobe of Principled
 * roughness ``rough`` sees it: the image's prefiltered levels (WORLD_ENV), else the SH light
 * convolved towards the cosine lobe with roughness. */
vec3 world_glossy_radiance(vec3 R, float rough)
{
#if WORLD_ENV
  return world_env_radiance(R, rough);
#else
  float t = rough * rough;
  return world_sh(R, vec2(mix(1.0, 2.0 / 3.0, t), mix(1.0, 0.25, t)));
#endif
}

/* The direction a GGX lobe of Principled roughness ``rough`` about ``N`` reads the prefiltered
 * world along, seen from ``V``: the mirror direction turned towards the normal as the lobe's
 * peak is at rougher lobes and grazing views (Lagarde and de Rousiers 2014, "Moving Frostbite to
 * Physically Based Rendering", the specular dominant direction); the mirror direction itself
 * at roughness 0. */
vec3 specular_dominant(vec3 N, vec3 V, float rough)
{
  float t = rough * rough;
  return normalize(mix(N, reflect(-V, N), (1.0 - t) * (sqrt(1.0 - t) + t)));
}

vec3 world_light(Lobe b, vec3 V, vec2 ab)
{
  vec3 scene_seen = vec3(0.0); /* what traced rays met of the scene (Glossy Indirect) */
  vec3 diffuse = b.albedo * world_sh(b.N, vec2(2.0 / 3.0, 0.25));
  vec3 R = reflect(-V, b.N);
  float t = b.rough * b.rough;
  vec3 Rd = specular_dominant(b.N, V, b.rough);
#if NODE_ANISO
  /* An anisotropic lobe: the world along ANISO_WORLD_RAYS reflections of visible normals a
   * pixel and sample (lib/anisotropy.glsl), each weighted by G2 / G1 (0 below the horizon) and
   * lightly blurred by half the short axis's roughness; over the isotropic lobe's albedo E,
   * which dfg carries, so the anisotropic lobe's own albedo replaces it. */
  vec3 radiance;
  if (b.ax != b.ay) {
    vec3 sum = vec3(0.0);
    float blur = sqrt(0.5 * min(b.ax, b.ay));
    for (int j = 0; j < ANISO_WORLD_RAYS; j++) {
      vec2 u = pixel_r2(83.0 + float(world_lobe), frame.sample_index * ANISO_WORLD_RAYS + j);
      vec3 L = ggx_aniso_reflection(b.N, b.T, b.B, V, b.ax, b.ay, u);
      sum += ggx_aniso_weight(b.N, b.T, b.B, V, L, b.ax, b.ay) * world_glossy_radiance(L, blur);
    }
    float e = ggx_albedo(sqrt(sqrt(b.ax * b.ay)), max(dot(b.N, V), 1e-4)).x;
    radiance = sum / (float(ANISO_WORLD_RAYS) * max(e, 1e-4));
  }
  else {
    radiance = world_glossy_radiance(Rd, b.rough);
  }
#else
  vec3 radiance = world_glossy_radiance(Rd, b.rough);
#endif
  vec3 dfg = b.f0.rgb * ab.x + ab.y;
#if NODE_FILM
  /* A Thin Film's dielectric (lit_bsdf.glsl lobe_setup), the metal's own. */
  dfg = mix(dfg, mix(b.film_dfg, b.metal_film_dfg, b.metal), b.film);
#endif
  vec3 specular = radiance * dfg;
#if WORLD_AO && WORLD_RATIO
  /* The occlusion goes into the ratio's sums (surface_world_light), the colour keeps U whole. */
  world_part_vis = vec2(world_visibility, gtao_specular(world_visibility, max(dot(b.N, V), 0.0), t));
#elif WORLD_AO
  diffuse *= world_visibility;
  specular *= gtao_specular(world_visibility, max(dot(b.N, V), 0.0), t);
#endif
#if WORLD_RATIO
  world_part_d = diffuse;
  world_part_s = specular * world_ratio_share(b.rough);
#endif
#if SSR || SSR_SETTLE || PLANAR || CUBES
  /* Where a traced ray meets the scene (weight h), the lobe reflects it, and the world's light
   * it hid goes: specular = radiance dfg (1 - h (1 - share)) + hit dfg h. The share the ratio
   * shadows keeps its own visibility (its U_s is never more than what is left of the world's
   * light, so the resolve stays >= 0); the rest, which the ratio leaves alone, takes the
   * ray's. Lobes from SSR_FADE to WORLD_RATIO_ROUGH fade their rays out; rougher lobes are
   * not traced. A Plane probe's capture (PLANAR) is asked first; the screen (SSR) takes what
   * it leaves: h = h_p + (1 - h_p) h_s, the hits weighted alike; the cube maps (CUBES) what
   * both leave. */
  float reach = 1.0 - smoothstep(SSR_FADE, WORLD_RATIO_ROUGH, b.rough);
  if (reach > 0.0 && b.weight > 0.0) {
    world_traced = true;
#  if SSR || PLANAR || CUBES
    vec3 xi = ssr_random(world_lobe);
    vec3 L = ssr_direction(b.N, V, b.rough, xi.xy);
    vec3 seen;
    float h = 0.0;
    vec3 hits = vec3(0.0);
    float w;
#    if PLANAR
    w = planar_trace(world_point, b.N, L, xi.z, seen);
    world_hit(reach * w, seen, h, hits);
#    endif
#    if SSR
    if (h < 1.0) {
      w = ssr_trace(world_point, b.N, L, xi.z, seen);
      world_hit(reach * w, seen, h, hits);
    }
#    endif
#    if CUBES
    if (h < 1.0) {
      w = cube_trace(world_point, b.N, L, xi.z, seen);
      world_hit(reach * w, seen, h, hits);
    }
#    endif
    specular = specular * (1.0 - h * (1.0 - world_ratio_share(b.rough)));
    scene_seen = hits * dfg;
#    if DEBUG_LIT
    debug_reflected = max(debug_reflected, h);
#    endif
#  endif
  }
#endif
#if LIGHT_PASS == LIGHT_PASS_DIFFUSE || LIGHT_PASS == LIGHT_PASS_SUBSURFACE
  return diffuse;
#elif LIGHT_PASS == LIGHT_PASS_GLOSSY
  return specular;
#elif LIGHT_PASS == LIGHT_PASS_GLOSSY_INDIRECT
  return scene_seen;
#elif LIGHT_PASS == LIGHT_PASS_GROUP && LIGHT_GROUP_WORLD
  return diffuse + specular;
#elif LIGHT_PASS != 0
  return vec3(0.0);
#else
  return diffuse + (specular + scene_seen);
#endif
}

#if NODE_COAT
/* The coat's reflection of the world: its radiance about the coat's dominant direction
 * (specular_dominant), blurred with the coat's roughness, times the coat's environment BRDF
 * and weight. */
vec3 coat_world_light(Coat c, vec3 V)
{
  return world_glossy_radiance(specular_dominant(c.N, V, c.rough), c.rough) * (c.weight * (c.f0 * c.ab.x + c.ab.y));
}
#endif

/* The world's light on every lobe of ``s``, summed by their weights (``ab``: each lobe's
 * environment BRDF, lobe_setup). With WORLD_AO the horizons are marched once and integrated for
 * each lobe's normal; with WORLD_RATIO each lobe's U goes into world_d and world_s, and a sample
 * with ambient occlusion adds its visibility to the sums as one sample's worth. */
vec3 surface_world_light(Surface s, vec2 ab[NODE_LOBES])
{
  world_point = s.P;
#if WORLD_AO
  mat3 ao_rotation = mat3(frame.view);
  vec3 ao_P = (frame.view * vec4(s.P, 1.0)).xyz;
  float ao_footprint = max(length(dFdx(ao_P)), length(dFdy(ao_P))); /* a pixel's size on the surface */
  /* A fragment behind the prepass's surface at its pixel is hidden (the lit pass draws the
   * same opaque surfaces) and its colour overwritten; one in front of it is a surface the
   * prepass leaves out (alpha-blended) and stays unoccluded. Neither reads the horizons. */
  float ao_front = texelFetch(ao_depth, ivec2(gl_FragCoord.xy), 0).r;
  GtaoHorizons ao_horizons;
  ao_horizons.valid = false;
  if (!(ao_front > 0.0) || abs(-ao_P.z - ao_front) <= 0.01 * ao_front) {
    ao_horizons = gtao_horizons_upsampled(ao_P, gl_FragCoord.xy, ao_footprint);
  }
#endif
  vec3 color = vec3(0.0);
#if VOLUMES
  /* What the media let through of it (features/volumes.py). */
  vec3 through = world_transmittance(s.P, s.Ng);
#endif
  for (int k = 0; k < NODE_LOBES; k++) {
    float w = s.lobe[k].weight;
#if VOLUMES
    w *= dot(through, vec3(1.0 / 3.0));
#endif
#if WORLD_AO
    world_visibility = gtao_visibility(ao_horizons, normalize(ao_rotation * s.lobe[k].N));
#  if DEBUG_LIT
    debug_world_ao += w * world_visibility;
#  endif
#endif
    world_lobe = k;
    color += w * world_light(s.lobe[k], s.V, ab[k]);
#if WORLD_RATIO
    world_d += w * world_part_d;
    world_s += w * world_part_s;
#  if WORLD_AO
    world_sums += w * world_ao_sums();
#  endif
#endif
  }
#if NODE_SHEEN
  /* The sheen: what the lobes keep under it, and its own light from the world: one direction
   * drawn from its lobe per pixel and sample (lib/sheen.glsl), the world there lightly blurred,
   * so the frame's samples converge to its integral (a diffuse lobe: occluded as the lobes'
   * diffuse is, the Diffuse passes). */
  color *= s.sheen.below;
#  if WORLD_RATIO
  world_d *= s.sheen.below;
  world_s *= s.sheen.below;
#  endif
#  if LIGHT_PASS == 0 || LIGHT_PASS == LIGHT_PASS_DIFFUSE || (LIGHT_PASS == LIGHT_PASS_GROUP && LIGHT_GROUP_WORLD)
  vec2 u = pixel_r2(37.0, frame.sample_index);
  vec3 sheen = s.sheen.color * s.sheen.ltc.z * world_glossy_radiance(sheen_direction(s.sheen, u), 0.3);
#    if VOLUMES
  sheen *= dot(through, vec3(1.0 / 3.0));
#    endif
#    if WORLD_RATIO
  world_d += sheen;
#    elif WORLD_AO
  sheen *= world_visibility;
#    endif
  color += sheen;
#    if DEBUG_TERM == 5 && NODE_COAT
  debug_term += sheen * s.coat.below;
#    elif DEBUG_TERM == 5
  debug_term += sheen;
#    endif
#  endif
#endif
#if NODE_COAT
  /* The coat: what reaches the lobes under it, and its own reflection of the world (not
   * traced against the scene, not occluded by WORLD_AO). */
  color *= s.coat.below;
#  if WORLD_RATIO
  world_d *= s.coat.below;
  world_s *= s.coat.below;
#  endif
#  if LIGHT_PASS == 0 || LIGHT_PASS == LIGHT_PASS_GLOSSY || (LIGHT_PASS == LIGHT_PASS_GROUP && LIGHT_GROUP_WORLD)
  vec3 coat = coat_world_light(s.coat, s.V);
#    if VOLUMES
  coat *= dot(through, vec3(1.0 / 3.0));
#    endif
  color += coat;
#    if WORLD_RATIO
  world_s += coat * world_ratio_share(s.coat.rough);
#    endif
#    if DEBUG_TERM == 4
  debug_term += coat;
#    endif
#  endif
#endif
  return color;
}


#if WORLD_RATIO
/* A direction of the world's light (``L.world``) adds to the ratio's sums, by lobe: diffuse and
 * specular, each weighted by its own f cos L / p. ``cosines``: each lobe's cosine term (0 where
 * the light is behind it). */
void world_direction(Surface s, LightData L, vec3 to_light, float irradiance, float visibility,
                     float NdotL[NODE_LOBES], float cosines[NODE_LOBES])
{
  vec3 E = L.color * irradiance;
  vec2 w = vec2(0.0);
  for (int k = 0; k < NODE_LOBES; k++) {
    if (NdotL[k] > 0.0) {
      vec3 f = lobe_brdf(s.lobe[k], s.V, to_light, NdotL[k], L);
      w += s.lobe[k].weight * world_direction_weights(E, s.lobe[k].albedo, f, cosines[k], L, s.lobe[k].rough);
    }
  }
  w = max(w, vec2(0.0));
  world_sums += vec4(visibility * w.x, w.x, visibility * w.y, w.y);
}
#endif

#endif /* PENUMBRA_LIB_LIT_WORLD */
