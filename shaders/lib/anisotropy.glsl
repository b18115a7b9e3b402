// requires: lib/common.glsl
#ifndef PENUMBRA_LIB_ANISOTROPY
#define PENUMBRA_LIB_ANISOTROPY

/* Anisotropic GGX (NODE_ANISO): the Principled BSDF's Anisotropic and Anisotropic Rotation and
 * the Glossy BSDF's Anisotropy, as Cycles draws them. The lobe's GGX roughness becomes
 * alpha_x = alpha k along the tangent T and alpha_y = alpha / k along B = N x T, each within
 * [0.002, 1] (Cycles clamps them to 1): k = 1 / sqrt(1 - 0.9 Anisotropic) for the Principled
 * BSDF, 1 / (1 + a) or 1 - a for the Glossy BSDF's Anisotropy a below or above 0. The
 * distribution and the height-correlated Smith masking-shadowing are the anisotropic ones
 * (Heitz 2014; Kulla and Conty 2017); its multiple-scattering gain is the isotropic lobe's of
 * alpha = sqrt(alpha_x alpha_y), as Cycles takes it. The world's light on it is read along
 * ANISO_WORLD_RAYS reflections of visible normals drawn each pixel and sample (Heitz 2018), each
 * weighted by G2 / G1 (their mean: the anisotropic lobe's own albedo), so the frame's samples
 * spread it along the lobe's long axis and lose what the lobe sends below the surface. */

#ifndef NODE_ANISO
#  define NODE_ANISO 0 /* an anisotropic lobe is drawn (engine/frame/programs.py material_defines) */
#endif

#if NODE_ANISO

/* GGX's anisotropic distribution times the height-correlated Smith visibility G / (4 N.L N.V)
 * for roughnesses ``ax`` along ``T`` and ``ay`` along ``B``, normal ``N``, view ``V``, light
 * ``L`` (N.L = ``NdotL`` > 0) and half vector ``H``. */
float ggx_aniso_d_vis(vec3 N, vec3 T, vec3 B, vec3 V, vec3 L, vec3 H, float NdotL, float ax, float ay)
{
  vec3 h = vec3(dot(T, H), dot(B, H), dot(N, H));
  vec3 hs = vec3(h.x / ax, h.y / ay, h.z);
  float d2 = dot(hs, hs);
  float D = 1.0 / (M_PI * ax * ay * d2 * d2);
  vec3 v = vec3(dot(T, V) * ax, dot(B, V) * ay, max(dot(N, V), 1e-4));
  vec3 l = vec3(dot(T, L) * ax, dot(B, L) * ay, NdotL);
  float gv = NdotL * length(v);
  float gl = v.z * length(l);
  return D * (0.5 / max(gv + gl, 1e-8));
}

/* The reflections of the world an anisotropic lobe reads per pixel and sample (lit_world.glsl). */
#define ANISO_WORLD_RAYS 4

/* Smith's Lambda of direction ``W`` (above the surface) for the anisotropic GGX. */
float ggx_aniso_lambda(vec3 N, vec3 T, vec3 B, vec3 W, float ax, float ay)
{
  float z = max(dot(N, W), 1e-4);
  vec3 w = vec3(dot(T, W) * ax, dot(B, W) * ay, z);
  return 0.5 * (length(w) / z - 1.0);
}

/* The weight of a reflection ``L`` drawn by ggx_aniso_reflection, f cos / pdf over the Fresnel:
 * G2(V, L) / G1(V) = (1 + Lambda(V)) / (1 + Lambda(V) + Lambda(L)) (height-correlated Smith), 0
 * where it points below the surface. Its mean over the draws is the lobe's albedo at F = 1. */
float ggx_aniso_weight(vec3 N, vec3 T, vec3 B, vec3 V, vec3 L, float ax, float ay)
{
  if (!(dot(N, L) > 0.0)) {
    return 0.0;
  }
  float lv = ggx_aniso_lambda(N, T, B, V, ax, ay);
  return (1.0 + lv) / (1.0 + lv + ggx_aniso_lambda(N, T, B, L, ax, ay));
}

/* A reflected direction for the uniforms ``u``: the view reflected about a visible normal of the
 * anisotropic GGX (Heitz 2018, "Sampling the GGX Distribution of Visible Normals"); weigh it by
 * ggx_aniso_weight (0 where it points below the surface). */
vec3 ggx_aniso_reflection(vec3 N, vec3 T, vec3 B, vec3 V, float ax, float ay, vec2 u)
{
  vec3 v = vec3(dot(T, V), dot(B, V), max(dot(N, V), 1e-4));
  vec3 vh = normalize(vec3(ax * v.x, ay * v.y, v.z));
  float l2 = vh.x * vh.x + vh.y * vh.y;
  vec3 t1 = (l2 > 1e-12) ? vec3(-vh.y, vh.x, 0.0) / sqrt(l2) : vec3(1.0, 0.0, 0.0);
  vec3 t2 = cross(vh, t1);
  float r = sqrt(u.x), phi = 2.0 * M_PI * u.y;
  float p1 = r * cos(phi), p2 = r * sin(phi);
  float s = 0.5 * (1.0 + vh.z);
  p2 = (1.0 - s) * sqrt(max(1.0 - p1 * p1, 0.0)) + s * p2;
  vec3 nh = p1 * t1 + p2 * t2 + sqrt(max(1.0 - p1 * p1 - p2 * p2, 0.0)) * vh;
  vec3 m = normalize(vec3(ax * nh.x, ay * nh.y, max(nh.z, 1e-6)));
  vec3 H = m.x * T + m.y * B + m.z * N;
  return reflect(-V, H); /* below the surface where the visible normal turns it there */
}

#endif

#endif /* PENUMBRA_LIB_ANISOTROPY */
