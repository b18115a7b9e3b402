// requires: lib/common.glsl lib/ggx_albedo.glsl lib/lit_surface.glsl lib/thin_film.glsl lib/anisotropy.glsl
#ifndef PENUMBRA_LIB_LIT_BSDF
#define PENUMBRA_LIB_LIT_BSDF

/* The surface's BSDF: Lambert diffuse under a GGX (or normalised Blinn/Phong, SPECULAR_MODEL)
 * specular layer, as the Principled BSDF layers them; the environment BRDF that weighs the
 * world's specular and takes the specular layer's energy out of the diffuse one below. */

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

#if NODE_FILM
/* The surface's Thin Film (weight, thickness nm, film IOR, base IOR): lib/lit_inputs.glsl sets
 * it before the lobes are set up. */
vec4 lit_film = vec4(0.0, 0.0, 1.33, 1.5);
#endif

/* GGX's distribution times the height-correlated Smith visibility G / (4 N.L N.V) for GGX
 * roughness ``alpha``, normal ``N``, view ``V``, light ``to_light`` (N.L = ``NdotL`` > 0) and
 * half vector ``H``: what each GGX lobe (the lobes' specular, the coat) multiplies its Fresnel by. */
float ggx_d_vis(vec3 N, vec3 V, vec3 H, float NdotL, float alpha)
{
  float NdotH = max(dot(N, H), 0.0);
  float NdotV = max(dot(N, V), 1e-4);
  float a2 = alpha * alpha;
  float dd = NdotH * NdotH * (a2 - 1.0) + 1.0;
  float D = a2 / (M_PI * dd * dd);
  float gv = NdotL * sqrt(NdotV * NdotV * (1.0 - a2) + a2);
  float gl = NdotV * sqrt(NdotL * NdotL * (1.0 - a2) + a2);
  return D * (0.5 / max(gv + gl, 1e-8));
}

/* One lobe's BSDF for light from ``to_light`` (N.L > 0): its diffuse and specular parts, each
 * scaled by the light's factors. */
vec3 lobe_brdf(Lobe b, vec3 V, vec3 to_light, float NdotL, LightData L)
{
#if SPECULAR_MODEL == SPECULAR_GGX
  vec3 H = normalize(to_light + V);
  /* Fresnel from f0.rgb towards f90 (f0.a: lobe_setup) along the exact dielectric curve
   * (fresnel_shape). */
  float fw = fresnel_shape(dot(to_light, H));
  vec3 F = b.f0.rgb + (b.f0.a - b.f0.rgb) * fw;
#  if NODE_FILM
  if (b.film > 0.0) {
    /* The film on the dielectric's specular and on the metal's (their Fresnel at the half vector). */
    float cos_h = dot(to_light, H);
    vec3 film = film_fresnel(cos_h, lit_film.y, lit_film.z, lit_film.w) * b.film_tint;
    if (b.metal > 0.0) {
      film = mix(film, film_fresnel_metal(cos_h, lit_film.y, lit_film.z, b.metal_f0, b.film_tint), b.metal);
    }
    F = mix(F, film, b.film);
  }
#  endif
  /* Times the multiple-scattering gain (ggx_ms_gain), as Cycles scales the lobe. */
#  if NODE_ANISO
  vec3 spec = F * (ggx_aniso_d_vis(b.N, b.T, b.B, V, to_light, H, NdotL, b.ax, b.ay) * b.ms);
#  else
  vec3 spec = F * (ggx_d_vis(b.N, V, H, NdotL, b.alpha) * b.ms);
#  endif
  return b.albedo / M_PI * L.diffuse_factor + spec * L.specular_factor;
#else
#  if SPECULAR_MODEL == SPECULAR_BLINN
  vec3 H = normalize(to_light + V);
  float spec = (b.shininess + 8.0) / (8.0 * M_PI) * pow(max(dot(b.N, H), 0.0), b.shininess);
#  else
  vec3 R = reflect(-to_light, b.N);
  float spec = (b.shininess + 2.0) / (2.0 * M_PI) * pow(max(dot(R, V), 0.0), b.shininess);
#  endif
  return b.albedo / M_PI * L.diffuse_factor + b.f0.rgb * spec * L.specular_factor;
#endif
}

/* The GGX lobe's multiple-scattering gain towards the viewer, 1 + F_ms (1 - E) / E (Kulla and
 * Conty 2017, as Cycles' microfacet_ggx_preserve_energy scales the lobe: F_ms = F_ss E_avg /
 * (1 - F_ss (1 - E_avg)), F_ss the Fresnel's cosine-weighted mean) for ``f`` the lobe's mean f0
 * and ``e`` its albedo E towards the viewer (ggx_albedo's x): what its value under each light
 * and its albedo (env_brdf) are multiplied by. */
float ggx_ms_gain(float f, float f90, float rough, float e)
{
  float e_avg = ggx_albedo_avg(rough);
  /* F_ss is a mean reflectance: within [0, 1] whatever f0 is. A metal's f0 is its base colour,
   * which may exceed 1 (an image's premultiplied texel, an HDR colour): unbounded, F_ss past
   * 1 / (1 - E_avg) turned the multiple-scattering term negative and the world's light on the
   * surface below zero. */
  float f_ss = clamp(f + (1.0 - f) * GGX_S_AVG * f90, 0.0, 1.0);
  float f_ms = f_ss * e_avg / (1.0 - f_ss * (1.0 - e_avg));
  return 1.0 + f_ms * (1.0 - e) / max(e, 1e-4);
}

/* The specular lobe's directional albedo as a scale and bias of f0 (the split sum's
 * environment BRDF): f0 a + b is what the lobe reflects of light from all directions, the
 * energy the diffuse layer below does not get and the weight of the world's specular. (E, S)
 * come from lib/ggx_albedo.glsl (GGX, height-correlated Smith, the Fresnel curve of
 * fresnel_shape). Multiple scattering between the microfacets adds 1 + F_ms (1 - E) / E (Kulla
 * and Conty 2017, as Cycles' microfacet_ggx_preserve_energy: F_ms = F_ss E_avg / (1 - F_ss
 * (1 - E_avg)), F_ss the Fresnel's cosine-weighted mean: ggx_ms_gain) as the gain ``ms``. ``es``:
 * the table's (E, S) at the lobe's roughness and view (looked up once per lobe for its uses).
 * The bias (the Fresnel rim) is scaled by ``f90``: a surface without specular has none. */
vec2 env_brdf(vec2 es, float f90, float ms)
{
  return vec2(max(es.x - es.y, 0.0), es.y * f90) * ms;
}

/* One lobe's shading values from its Principled parameters, with normal ``N`` and ``weight``;
 * ``ab``: its environment BRDF (what the world's specular is weighted by). */
Lobe lobe_setup(vec3 base, float rough, float metal, vec4 spec, vec3 N, vec3 V, float weight, out vec2 ab)
{
  Lobe b;
  b.N = N;
  b.weight = weight;
  rough = clamp(rough, 0.0, 1.0);
  b.rough = rough;
  /* The dielectric's F0 (rgb, tinted) and untinted f0 (a): from IOR, Specular IOR Level and
   * Specular Tint (node_principled_f0; materials.dielectric_f0 for a read material). */
  spec = max(spec, vec4(0.0));
  metal = clamp(metal, 0.0, 1.0);
  b.albedo = base * (1.0 - metal);
  /* Schlick's f90: 1, but a surface without specular (f0 ~ 0) has no Fresnel rim either, as
   * the Principled BSDF at IOR 1 or Specular IOR Level 0 (the tint does not change it: F90 is
   * white in Blender's generalized Schlick). */
  float f90 = clamp(50.0 * mix(spec.a, dot(base, vec3(0.3333)), metal), 0.0, 1.0);
  b.f0 = vec4(mix(spec.rgb, base, metal), f90);
  float a = max(rough * rough, 0.02);
  b.shininess = 2.0 / (a * a) - 2.0;
  b.alpha = max(rough * rough, 0.002);

  /* Energy: light reflected by the specular layer does not reach the diffuse one below (the
   * Principled BSDF's layering), estimated per pixel from the directional albedo. */
  float NdotV = max(dot(N, V), 1e-4);
  vec2 es = ggx_albedo(rough, NdotV); /* looked up once for the lobe's three uses below */
  b.ms = ggx_ms_gain(dot(b.f0.rgb, vec3(0.3333)), f90, rough, es.x);
  ab = env_brdf(es, f90, b.ms);
  /* Metallic mixes a metal and a dielectric; only the dielectric's own specular sits over its
   * diffuse, per channel (a tinted specular takes its own colour out of the diffuse). */
  float f90_d = clamp(50.0 * spec.a, 0.0, 1.0);
  vec2 ab_dielectric = env_brdf(es, f90_d, ggx_ms_gain(dot(spec.rgb, vec3(0.3333)), f90_d, rough, es.x));
  vec3 reflected = spec.rgb * ab_dielectric.x + ab_dielectric.y;
#if NODE_FILM
  /* A Thin Film: the dielectric reflects the film's reflectance towards the viewer times the
   * lobe's albedo at F = 1, and the diffuse below loses that instead. */
  b.film = clamp(lit_film.x, 0.0, 1.0);
  b.metal = metal;
  b.metal_f0 = base;
  vec2 ab_one = env_brdf(es, 1.0, ggx_ms_gain(1.0, 1.0, rough, es.x));
  /* Specular Tint (the tinted F0 over the untinted) tints the film's reflectance, as Cycles'. */
  b.film_tint = (spec.a > 1e-6) ? clamp(spec.rgb / spec.a, 0.0, 1e6) : vec3(1.0);
  b.film_dfg = film_fresnel(NdotV, lit_film.y, lit_film.z, lit_film.w) * (ab_one.x + ab_one.y) * b.film_tint;
  /* The metal's, as Cycles films its F82-tint metal (lib/thin_film.glsl film_fresnel_metal). */
  b.metal_film_dfg = (metal > 0.0) ? film_fresnel_metal(NdotV, lit_film.y, lit_film.z, base, b.film_tint) *
                                         (ab_one.x + ab_one.y) :
                                     vec3(0.0);
  reflected = mix(reflected, b.film_dfg, b.film);
#endif
  b.albedo *= clamp(1.0 - reflected, 0.0, 1.0);
  return b;
}

#if NODE_ANISO
/* The lobe's anisotropy (lib/anisotropy.glsl) from ``aniso`` (tangent, ln k): its frame about
 * its own normal and its roughness along each axis; isotropic where the tangent or k vanish.
 * Where a roughness is clamped, its albedo (``ab``) and multiple-scattering gain are the
 * isotropic lobe's of alpha = sqrt(alpha_x alpha_y), as Cycles takes them. */
void lobe_anisotropy(inout Lobe b, vec4 aniso, vec3 V, inout vec2 ab)
{
  vec3 T = aniso.xyz - b.N * dot(b.N, aniso.xyz);
  float tl = length(T);
  vec3 up = (abs(b.N.z) < 0.9) ? vec3(0.0, 0.0, 1.0) : vec3(1.0, 0.0, 0.0);
  b.T = (tl > 1e-6) ? T / tl : normalize(cross(up, b.N));
  b.B = cross(b.N, b.T);
  float k = (tl > 1e-6) ? exp(clamp(aniso.w, -10.0, 10.0)) : 1.0;
  b.ax = clamp(b.alpha * k, 0.002, 1.0);
  b.ay = clamp(b.alpha / k, 0.002, 1.0);
  float rough = sqrt(sqrt(b.ax * b.ay));
  if (abs(rough - b.rough) > 1e-3) {
    float NdotV = max(dot(b.N, V), 1e-4);
    float f = dot(b.f0.rgb, vec3(0.3333));
    vec2 es = ggx_albedo(rough, NdotV);
    b.ms = ggx_ms_gain(f, b.f0.a, rough, es.x);
    ab = env_brdf(es, b.f0.a, b.ms);
  }
}
#endif

#if NODE_COAT
/* The coat over the lobes (Blender's Principled BSDF, as Cycles layers it): a dielectric GGX
 * of Coat Roughness and IOR with its own normal, weighted by Coat Weight. What it reflects
 * (its directional albedo towards the viewer, E = f0 A + B from the same table as the
 * lobes' specular, env_brdf) does not reach the lobes below; what does is tinted by Coat Tint
 * over the path through the coat, tint^(1 / cos) with cos the refracted view's (Beer's law
 * with the tint the transmittance straight across). ``params``: (weight, roughness, IOR, 0). */
Coat coat_setup(vec4 params, vec3 tint, vec3 N, vec3 V)
{
  Coat c;
  c.N = N;
  c.weight = clamp(params.x, 0.0, 1.0);
  c.rough = clamp(params.y, 0.0, 1.0);
  c.alpha = max(c.rough * c.rough, 0.002);
  float ior = max(params.z, 1.0);
  float r = (ior - 1.0) / (ior + 1.0);
  c.f0 = r * r;
  float NdotV = max(dot(N, V), 1e-4);
  /* Its Fresnel rim follows f0 as the lobes' does (lobe_setup): a coat of IOR 1 reflects nothing. */
  float f90 = clamp(50.0 * c.f0, 0.0, 1.0);
  vec2 es = ggx_albedo(c.rough, NdotV);
  c.ms = ggx_ms_gain(c.f0, f90, c.rough, es.x);
  c.ab = env_brdf(es, f90, c.ms);
  float albedo = clamp(c.f0 * c.ab.x + c.ab.y, 0.0, 1.0);
  float cos_t = sqrt(max(1.0 - (1.0 - NdotV * NdotV) / (ior * ior), 1e-8));
  vec3 through = pow(clamp(tint, vec3(1e-6), vec3(1.0)), vec3(1.0 / cos_t));
  c.below = (1.0 - c.weight * albedo) * mix(vec3(1.0), through, c.weight);
  return c;
}

/* The coat's reflection of light from ``to_light`` (N.L > 0 for the coat's normal): GGX with
 * height-correlated Smith visibility and the dielectric Fresnel of fresnel_shape from f0. */
float coat_brdf(Coat c, vec3 V, vec3 to_light, float NdotL)
{
  vec3 H = normalize(to_light + V);
  float f90 = clamp(50.0 * c.f0, 0.0, 1.0);
  float F = c.f0 + (f90 - c.f0) * fresnel_shape(dot(to_light, H));
  return c.weight * F * ggx_d_vis(c.N, V, H, NdotL, c.alpha) * c.ms;
}
#endif

#endif /* PENUMBRA_LIB_LIT_BSDF */
