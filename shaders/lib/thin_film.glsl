// requires: lib/common.glsl lib/lit_surface.glsl lib/thin_film_table.glsl
#ifndef PENUMBRA_LIB_THIN_FILM
#define PENUMBRA_LIB_THIN_FILM

/* A thin dielectric film (the Principled BSDF's Thin Film: NODE_FILM) on a dielectric or, as
 * Cycles films its metals, on a conductor: its reflectance in linear Rec. 709. The Airy sum of
 * the waves the film's two interfaces reflect (Belcour and Barla 2017, "A Practical Extension to
 * Microfacet Theory for the Modeling of Varying Iridescence": R12 + Rs and three orders m of
 * 2 C_m cos(m (delta + phi))), integrated against the colour matching functions in Fourier space:
 * each order is Re(exp(i m phi) S(m OPD)), S the table of lib/thin_film_table.glsl
 * (tools/make_film_table.py). devkit/analytic.py integrates the exact Airy reflectance over the
 * spectrum instead (thin_film_fresnel, thin_film_conductor): the tests' reference. Air above; a
 * film of ``film_ior`` and ``thickness`` (nm), below 1 nm fading to none, as Cycles'. */

#if NODE_FILM

vec2 film_cmul(vec2 a, vec2 b)
{
  return vec2(a.x * b.x - a.y * b.y, a.x * b.y + a.y * b.x);
}

vec2 film_cdiv(vec2 a, vec2 b)
{
  return vec2(a.x * b.x + a.y * b.y, a.y * b.x - a.x * b.y) / max(dot(b, b), 1e-30);
}

/* The principal square root of z. */
vec2 film_csqrt(vec2 z)
{
  float r = length(z);
  float re = sqrt(max(0.5 * (r + z.x), 0.0));
  float im = sqrt(max(0.5 * (r - z.x), 0.0));
  return vec2(re, (z.y < 0.0) ? -im : im);
}

/* The s- and p-polarised reflection amplitudes (complex) at cosine ``c`` from a dielectric of
 * index ``n1`` into ``n2`` (complex: n + i k; a dielectric's k is 0, and past the critical
 * angle the amplitude's phase is total internal reflection's). */
void film_amplitudes(float c, float n1, vec2 n2, out vec2 rs, out vec2 rp)
{
  vec2 ratio = film_cdiv(vec2(n1, 0.0), n2);
  vec2 ratio2 = film_cmul(ratio, ratio);
  vec2 c2 = film_csqrt(vec2(1.0, 0.0) - ratio2 * (1.0 - c * c));
  vec2 n1c = vec2(n1 * c, 0.0);
  vec2 n2c2 = film_cmul(n2, c2);
  rs = film_cdiv(n1c - n2c2, n1c + n2c2);
  vec2 n2c = n2 * c;
  vec2 n1c2 = n1 * c2;
  rp = film_cdiv(n2c - n1c2, n2c + n1c2);
}

/* S(x) per channel (complex: re, im) from the table, 0 past its reach. */
void film_sensitivity(float x, out vec3 re, out vec3 im)
{
  float p = x / FILM_REACH * float(FILM_TABLE_SIZE - 1);
  if (!(p < float(FILM_TABLE_SIZE - 1))) {
    re = im = vec3(0.0);
    return;
  }
  int i = int(p);
  float f = p - float(i);
  vec3 are = mix(FILM_A_RE[i], FILM_A_RE[i + 1], f);
  vec3 aim = mix(FILM_A_IM[i], FILM_A_IM[i + 1], f);
  vec3 turn = 6.283185307179586 * fract(x * FILM_NU); /* exp(i 2 pi x nu), its phase taken mod 1 turn */
  vec3 cs = cos(turn), sn = sin(turn);
  re = are * cs - aim * sn;
  im = are * sn + aim * cs;
}

/* One polarisation's Airy sum for channel weights: top reflectance ``R12`` (real amplitude's
 * sign in ``top_phase``: 0 or pi), the bottom's reflectance ``R23`` and phase ``phi23`` per
 * channel, the optical path difference ``opd``; ``S`` the three orders' sensitivities. */
vec3 film_airy(float R12, float top_phase, vec3 R23, vec3 phi23, vec3 s_re[3], vec3 s_im[3])
{
  float T121 = 1.0 - R12;
  vec3 R123 = clamp(R12 * R23, vec3(1e-7), vec3(0.9999));
  vec3 r123 = sqrt(R123);
  vec3 Rs = T121 * T121 * R23 / (vec3(1.0) - R123);
  vec3 phi = vec3(M_PI - top_phase) + phi23; /* the round trip's phase: r21 = -r12, then r23 */
  vec3 I = R12 + Rs;
  vec3 Cm = Rs - T121;
  for (int m = 1; m <= 3; m++) {
    Cm *= r123;
    vec3 a = float(m) * phi;
    I += 2.0 * Cm * (cos(a) * s_re[m - 1] - sin(a) * s_im[m - 1]);
  }
  return I;
}

/* The film's reflectance (linear Rec. 709) at cosine ``c`` from air over a base of complex
 * index per channel ``base_n`` + i ``base_k``; ``base_R``: the base's reflectance under the
 * film per channel (both polarisations), or negative to take the amplitudes' own. */
vec3 film_fresnel_base(float c, float thickness, float film_ior, vec3 base_n, vec3 base_k, vec3 base_R)
{
  c = clamp(c, 1e-4, 1.0);
  float d = max(thickness, 0.0);
  float eta2 = mix(1.0, max(film_ior, 1.0), smoothstep(0.0, 1.0, d));
  float c2 = sqrt(max(1.0 - (1.0 - c * c) / (eta2 * eta2), 0.0));
  vec2 rs12, rp12;
  film_amplitudes(c, 1.0, vec2(eta2, 0.0), rs12, rp12);
  float opd = 2.0 * eta2 * d * c2;
  vec3 s_re[3], s_im[3];
  for (int m = 1; m <= 3; m++) {
    film_sensitivity(float(m) * opd, s_re[m - 1], s_im[m - 1]);
  }
  vec3 Rs23, Rp23, phis, phip;
  for (int ch = 0; ch < 3; ch++) {
    vec2 rs, rp;
    film_amplitudes(c2, eta2, vec2(base_n[ch], base_k[ch]), rs, rp);
    Rs23[ch] = (base_R[ch] >= 0.0) ? base_R[ch] : dot(rs, rs);
    Rp23[ch] = (base_R[ch] >= 0.0) ? base_R[ch] : dot(rp, rp);
    phis[ch] = atan(rs.y, rs.x);
    phip[ch] = atan(rp.y, rp.x);
  }
  vec3 Rs = film_airy(rs12.x * rs12.x, (rs12.x < 0.0) ? M_PI : 0.0, Rs23, phis, s_re, s_im);
  vec3 Rp = film_airy(rp12.x * rp12.x, (rp12.x < 0.0) ? M_PI : 0.0, Rp23, phip, s_re, s_im);
  return clamp(0.5 * (Rs + Rp), vec3(0.0), vec3(1.0));
}

/* A film on a dielectric of ``base_ior``. */
vec3 film_fresnel(float c, float thickness, float film_ior, float base_ior)
{
  return film_fresnel_base(c, thickness, film_ior, vec3(max(base_ior, 1.0)), vec3(0.0), vec3(-1.0));
}

/* Cycles' F82-tint metal (Kutz et al., "Novel Aspects of the Adobe Standard Material"):
 * Schlick's Fresnel from ``f0`` less b cos (1 - cos)^6; b from the value at 82 degrees. */
vec3 f82_fresnel(float c, vec3 f0, vec3 b)
{
  float s = clamp(1.0 - c, 0.0, 1.0);
  float s5 = s * s * s * s * s;
  return clamp(f0 + (vec3(1.0) - f0) * s5 - b * (c * s5 * s), vec3(0.0), vec3(1.0));
}

/* The b whose F82 model has the value ``f82`` at 82 degrees. */
vec3 f82_b(vec3 f0, vec3 f82)
{
  const float f = 6.0 / 7.0;
  const float f5 = f * f * f * f * f;
  return (7.0 / (f5 * f)) * (f0 + (vec3(1.0) - f0) * f5 - f82);
}

/* A film on a metal of F82-tint ``f0`` and ``tint``, as Cycles films its Principled metal: the
 * metal's n and k from F0 and its value at 82 degrees read as Gulbrandsen's reflectivity and
 * edge tint ("Artist Friendly Metallic Fresnel", 2014); under the film, its reflectance the F82
 * model's at the film's index and its phase the complex Fresnel's. */
vec3 film_fresnel_metal(float c, float thickness, float film_ior, vec3 f0, vec3 tint)
{
  f0 = clamp(f0, vec3(0.0), vec3(1.0));
  const float f = 6.0 / 7.0;
  const float f5 = f * f * f * f * f;
  vec3 b = (f0 + (vec3(1.0) - f0) * f5) * (7.0 / (f5 * f)) * (vec3(1.0) - clamp(tint, vec3(0.0), vec3(1e6)));
  vec3 g = f82_fresnel(1.0 / 7.0, f0, b);
  vec3 r = min(f0, vec3(0.999));
  vec3 sr = sqrt(r);
  vec3 n = mix((vec3(1.0) + sr) / (vec3(1.0) - sr), (vec3(1.0) - r) / (vec3(1.0) + r), g);
  vec3 k = sqrt(max((r * (n + 1.0) * (n + 1.0) - (n - 1.0) * (n - 1.0)) / (vec3(1.0) - r), vec3(0.0)));
  float d = max(thickness, 0.0);
  float eta2 = mix(1.0, max(film_ior, 1.0), smoothstep(0.0, 1.0, d));
  float c2 = sqrt(max(1.0 - (1.0 - c * c) / (eta2 * eta2), 0.0));
  vec3 rn = n / eta2, rk2 = (k / eta2) * (k / eta2);
  vec3 film_f0 = ((rn - 1.0) * (rn - 1.0) + rk2) / ((rn + 1.0) * (rn + 1.0) + rk2);
  vec3 under = f82_fresnel(c2, film_f0, f82_b(film_f0, g));
  return film_fresnel_base(c, thickness, film_ior, n, k, under);
}

#endif

#endif /* PENUMBRA_LIB_THIN_FILM */
