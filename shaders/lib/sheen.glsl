// requires: lib/common.glsl lib/sheen_ltc.glsl
#ifndef PENUMBRA_LIB_SHEEN
#define PENUMBRA_LIB_SHEEN

/* The Principled BSDF's Sheen (NODE_SHEEN): Blender's microfiber sheen, Zeltner, Burley and
 * Chiang's "Practical Multiple-Scattering Sheen Using Linearly Transformed Cosines" (2022), as
 * Cycles layers it: over the lobes, under the coat, on the surface's shading normal. Its light
 * times the cosine is colour x R x D(w), D a clamped cosine linearly transformed (Heitz et al.
 * 2016) by (a, b), R its directional albedo, both from lib/sheen_ltc.glsl at (roughness, N.V), in
 * the frame whose x axis is the view projected on the surface. The lobes below it keep
 * 1 - max(colour R) of their light (Cycles' closure_layering_weight). A diffuse lobe in Blender's
 * passes. Compiled only into variants that draw a sheen. */

#if NODE_SHEEN

struct Sheen {
  vec3 N, T, B;
  vec3 color; /* Sheen Weight x Sheen Tint */
  vec3 ltc;   /* (a, b, R); 0 where the lobe is empty */
  float below; /* what the lobes under it keep */
};

/* The sheen of colour ``params.rgb`` and roughness ``params.w`` on normal ``N`` (on the viewer's
 * side) seen from ``V``; ``layered``: the share of it over the lobes (1: a Principled BSDF's; a
 * Sheen BSDF's sits beside them and takes nothing from them). */
Sheen sheen_setup(vec4 params, float layered, vec3 N, vec3 V)
{
  Sheen sh;
  sh.N = N;
  sh.color = max(params.rgb, vec3(0.0));
  float mu = dot(N, V);
  vec3 t = V - N * mu;
  float tl = length(t);
  /* Seen along the normal the frame's azimuth is free (the lobe is symmetric there). */
  vec3 any_t = (abs(N.z) < 0.9) ? vec3(0.0, 0.0, 1.0) : vec3(1.0, 0.0, 0.0);
  sh.T = (tl > 1e-6) ? t / tl : normalize(cross(any_t, N));
  sh.B = cross(N, sh.T);
  sh.ltc = sheen_ltc(params.w, clamp(mu, 0.0, 1.0));
  if (abs(sh.ltc.x) < 1e-5 || sh.ltc.z < 1e-5) {
    sh.ltc = vec3(0.0); /* an invalid transform: no lobe, as Cycles skips it */
  }
  vec3 albedo = sh.color * sh.ltc.z;
  sh.below = clamp(1.0 - clamp(layered, 0.0, 1.0) * max(albedo.r, max(albedo.g, albedo.b)), 0.0, 1.0);
  return sh;
}

/* The sheen's reflection of light from ``to_light``, times the cosine (D carries it). */
vec3 sheen_light(Sheen sh, vec3 to_light)
{
  vec3 o = vec3(dot(sh.T, to_light), dot(sh.B, to_light), dot(sh.N, to_light));
  if (!(o.z > 0.0)) {
    return vec3(0.0);
  }
  float a = sh.ltc.x, b = sh.ltc.y;
  float k = a * o.x + b * o.z;
  float len2 = k * k + a * a * o.y * o.y + o.z * o.z;
  float q = a / len2;
  return sh.color * (sh.ltc.z * o.z / M_PI * q * q);
}

/* A direction drawn from the sheen's lobe for uniforms ``u``: a cosine-distributed direction
 * transformed by the lobe's matrix (x - b z, y, a z up to scale), whose density is D itself, so
 * the world's radiance there times R is an unbiased estimate of the sheen's light from it. */
vec3 sheen_direction(Sheen sh, vec2 u)
{
  float r = sqrt(u.x), phi = 2.0 * M_PI * u.y;
  vec3 o = vec3(r * cos(phi), r * sin(phi), sqrt(max(1.0 - u.x, 0.0)));
  vec3 d = (o.x - sh.ltc.y * o.z) * sh.T + o.y * sh.B + sh.ltc.x * o.z * sh.N;
  float l = length(d);
  return (l > 1e-12) ? d / l : sh.N;
}

#endif

#endif /* PENUMBRA_LIB_SHEEN */
