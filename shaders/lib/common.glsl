// requires:
#ifndef PENUMBRA_LIB_COMMON
#define PENUMBRA_LIB_COMMON

#define M_PI 3.14159265358979323846

float saturate(float x) { return clamp(x, 0.0, 1.0); }

bool is_finite(float x) { return !(isnan(x) || isinf(x)); }

/* Replace NaN/Inf components by 0 so one bad pixel cannot spread through a filter. */
vec4 sanitize(vec4 c)
{
  return vec4(is_finite(c.r) ? c.r : 0.0,
              is_finite(c.g) ? c.g : 0.0,
              is_finite(c.b) ? c.b : 0.0,
              is_finite(c.a) ? c.a : 0.0);
}

#endif /* PENUMBRA_LIB_COMMON */
