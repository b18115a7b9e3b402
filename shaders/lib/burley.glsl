// requires:
#ifndef PENUMBRA_LIB_BURLEY
#define PENUMBRA_LIB_BURLEY

/* Burley's normalized diffusion profile (Christensen and Burley 2015, "Approximate Reflectance
 * Profiles for Efficient Subsurface Scattering", equation 3), as Cycles evaluates and samples it
 * (kernel/closure/bssrdf.h): for a distance d per channel, over the surface's plane
 *   R(r) = (exp(-r / d) + exp(-r / 3d)) / (8 pi d r),   integrating to 1,
 * truncated at BURLEY_TRUNCATE d. Its radial density (R times 2 pi r) is burley_radial; a
 * radius is drawn from it by inverting its CDF (burley_sample). devkit/analytic.py has the
 * numpy twins (burley_radial, burley_cdf, burley_sample). */

#define BURLEY_TRUNCATE 16.0
#define BURLEY_TRUNCATE_CDF 0.9963790093708328 /* the CDF at BURLEY_TRUNCATE */

/* R(r) 2 pi r: the density of the radius r (>= 0) for the distance d (> 0). */
float burley_radial(float d, float r)
{
  if (r >= BURLEY_TRUNCATE * d) {
    return 0.0;
  }
  float e3 = exp(-r / (3.0 * d));
  return (e3 * e3 * e3 + e3) / (4.0 * d);
}

/* The radius, in units of d, whose CDF 1 - exp(-r) / 4 - 3 exp(-r / 3) / 4 is ``xi`` (in
 * [0, BURLEY_TRUNCATE_CDF]): Newton's method from a fitted first guess (ten steps at most;
 * three or four suffice). */
float burley_root(float xi)
{
  float r = (xi <= 0.9) ? exp(xi * xi * 2.4) - 1.0 : 15.0;
  for (int i = 0; i < 10; i++) {
    float e3 = exp(-r / 3.0);
    float e = e3 * e3 * e3;
    float f = 1.0 - 0.25 * e - 0.75 * e3 - xi;
    float df = 0.25 * (e + e3);
    if (abs(f) < 1e-6 || df <= 0.0) {
      break;
    }
    r = max(r - f / df, 0.0);
  }
  return r;
}

/* A radius drawn from burley_radial(d, .) by ``u`` in [0, 1). */
float burley_sample(float d, float u)
{
  return burley_root(u * BURLEY_TRUNCATE_CDF) * d;
}

/* The share of the light entering one face of a slab ``s`` thick that leaves the other: the
 * profile integrated over the plane at that depth, (exp(-s / d) + 3 exp(-s / 3d)) / 4. */
float burley_through(float d, float s)
{
  if (d <= 0.0) {
    return 0.0;
  }
  float e3 = exp(-s / (3.0 * d));
  return 0.25 * (e3 * e3 * e3 + 3.0 * e3);
}

#endif /* PENUMBRA_LIB_BURLEY */
