/* The gathering film (engine/frame/sampling.py ``gathers``, film.Film.accumulate): a film
 * pixel takes each sample from every sample pixel within the filter's reach, each weighted by
 * the Blackman-Harris window at the distance between the pixel's centre and the point the
 * sample pixel shaded (its centre minus the sample's image shift), separable in x and y, as
 * EEVEE's film gathers (Film::update_sample_table, film_filter_weight). film_source returns
 * that weighted mean; the caller's ``scale`` is the sample's total weight (the same sum, made
 * in Python), so the accumulation gains sum(w c) and the weight target sum(w). Outside the
 * image the edge pixel stands in (a constant image stays constant there); a non-finite sample
 * takes no part (it does not spread). Under adaptive sampling a converged pixel stays shaded
 * while a pixel within the reach has not converged (converged_depth.frag.glsl), so every
 * sample gathered is this sample's. Without GATHER, the pixel's own sample. */

#ifndef FILM_GATHER_GLSL
#define FILM_GATHER_GLSL

#ifndef GATHER
#  define GATHER 0
#endif

#if GATHER
float gather_window(float x)
{
  float t = x / gather_width + 0.5;
  if (t <= 0.0 || t >= 1.0) {
    return 0.0;
  }
  float a = 6.283185307179586 * t;
  return 0.35875 - 0.48829 * cos(a) + 0.14128 * cos(2.0 * a) - 0.01168 * cos(3.0 * a);
}

vec4 film_source(sampler2D tex, ivec2 p)
{
  ivec2 last = textureSize(tex, 0) - 1;
  vec4 sum = vec4(0.0);
  float used = 0.0;
  for (int j = -gather_reach; j <= gather_reach; j++) {
    float wy = gather_window(float(j) - gather_shift.y);
    if (wy <= 0.0) {
      continue;
    }
    for (int i = -gather_reach; i <= gather_reach; i++) {
      float w = wy * gather_window(float(i) - gather_shift.x);
      if (w <= 0.0) {
        continue;
      }
      vec4 c = texelFetch(tex, clamp(p + ivec2(i, j), ivec2(0), last), 0);
      if (any(isnan(c)) || any(isinf(c))) {
        continue;
      }
      sum += w * c;
      used += w;
    }
  }
  return (used > 0.0) ? sum / used : vec4(0.0);
}
#else
vec4 film_source(sampler2D tex, ivec2 p)
{
  return texelFetch(tex, p, 0);
}
#endif

#endif
