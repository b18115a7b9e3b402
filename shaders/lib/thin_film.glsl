// requires: lib/common.glsl
#ifndef PENUMBRA_LIB_THIN_FILM
#define PENUMBRA_LIB_THIN_FILM

/* A thin dielectric film on a dielectric (the Principled BSDF's Thin Film: NODE_FILM): its
 * reflectance, the Airy summation of the waves the film's two interfaces reflect, integrated
 * against the CIE sensitivities in Fourier space (Belcour and Barla 2017, "A Practical
 * Extension to Microfacet Theory for the Modeling of Varying Iridescence": their Gaussian fit
 * of the sensitivities, the DC term and three pairs of Diracs), in linear Rec. 709 white-balanced
 * to the sensitivities' equal-energy white. Air above;
 * the film of ``film_ior`` and ``thickness`` (nm); the base of ``base_ior`` below. */

/* The XYZ sensitivities at optical path difference ``opd`` (nm) with phase ``shift``. */
vec3 film_sensitivity(float opd, float shift)
{
  float phase = 2.0 * M_PI * opd * 1e-9;
  const vec3 val = vec3(5.4856e-13, 4.4201e-13, 5.2481e-13);
  const vec3 pos = vec3(1.6810e+06, 1.7953e+06, 2.2084e+06);
  const vec3 var = vec3(4.3278e+09, 9.3046e+09, 6.6121e+09);
  vec3 xyz = val * sqrt(2.0 * M_PI * var) * cos(pos * phase + shift) * exp(-var * phase * phase);
  xyz.x += 9.7470e-14 * sqrt(2.0 * M_PI * 4.5282e+09) * cos(2.2399e+06 * phase + shift) *
           exp(-4.5282e+09 * phase * phase);
  return xyz / 1.0685e-7;
}

/* The s- and p-polarised reflectances of the interface from index n1 to n2 at cosine ``c``,
 * and their phase shifts (0 or pi; total internal reflection: the complex shifts). */
void film_interface(float c, float n1, float n2, out vec2 R, out vec2 phi)
{
  float s2 = 1.0 - c * c;
  float nr = n1 / n2;
  if (nr * nr * s2 > 1.0) {
    R = vec2(1.0);
    float t = sqrt(max(s2 - 1.0 / (nr * nr), 0.0)) / max(c, 1e-6);
    phi = 2.0 * atan(vec2(-nr * nr * t, -t));
    return;
  }
  float c2 = sqrt(max(1.0 - nr * nr * s2, 0.0));
  vec2 r = vec2((n2 * c - n1 * c2) / (n2 * c + n1 * c2), (n1 * c - n2 * c2) / (n1 * c + n2 * c2));
  phi = vec2(r.x < 0.0 ? M_PI : 0.0, r.y < 0.0 ? M_PI : 0.0);
  R = r * r;
}

/* The film's reflectance (RGB, linear Rec. 709) at cosine ``c`` from air. A film thinner than
 * 30 nm fades to none (its index to the air's), as the published model does. */
vec3 film_fresnel(float c, float thickness, float film_ior, float base_ior)
{
  c = clamp(c, 1e-4, 1.0);
  float d = max(thickness, 0.0);
  float eta2 = mix(1.0, max(film_ior, 1.0), smoothstep(0.0, 30.0, d));
  float c2 = sqrt(max(1.0 - (1.0 - c * c) / (eta2 * eta2), 0.0));
  vec2 R12, phi12;
  film_interface(c, 1.0, eta2, R12, phi12);
  vec2 T121 = vec2(1.0) - R12;
  vec2 phi21 = vec2(M_PI) - phi12;
  vec2 R23, phi23;
  film_interface(c2, eta2, max(base_ior, 1.0), R23, phi23);
  float opd = 2.0 * eta2 * d * c2;
  vec2 phi2 = phi21 + phi23;
  vec2 R123 = clamp(R12 * R23, vec2(1e-7), vec2(0.9999));
  vec2 r123 = sqrt(R123);
  vec2 Rs = T121 * T121 * R23 / (vec2(1.0) - R123);
  vec3 I = 0.5 * (R12.x + Rs.x + R12.y + Rs.y) * film_sensitivity(0.0, 0.0);
  vec2 Cm = Rs - T121;
  for (int m = 1; m <= 3; m++) {
    Cm *= r123;
    vec3 Ss = 2.0 * film_sensitivity(float(m) * opd, float(m) * phi2.x);
    vec3 Sp = 2.0 * film_sensitivity(float(m) * opd, float(m) * phi2.y);
    I += 0.5 * (Cm.x * Ss + Cm.y * Sp);
  }
  /* XYZ to linear Rec. 709, white balanced so that the sensitivities' own white (the DC
   * term's, equal energy) is Rec. 709's white: a film that reflects every wavelength alike
   * (no film at all) reflects white. */
  const mat3 XYZ_TO_REC709 = mat3(3.2404542, -0.9692660, 0.0556434, -1.5371385, 1.8760108, -0.2040259, -0.4985314,
                                  0.0415560, 1.0572252);
  vec3 white = XYZ_TO_REC709 * film_sensitivity(0.0, 0.0);
  return clamp((XYZ_TO_REC709 * I) / white, vec3(0.0), vec3(1.0));
}

#endif /* PENUMBRA_LIB_THIN_FILM */
