// requires:
#ifndef PENUMBRA_LIB_FILM_GATHER
#define PENUMBRA_LIB_FILM_GATHER

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

#ifndef GATHER
#  define GATHER 0
#endif

#if GATHER
/* The window's weight of sample pixel t (-GATHER_REACH .. GATHER_REACH) along one axis: the
 * Blackman-Harris window at the distance to the point it shaded, made in Python
 * (sampling.gather_uniforms) and padded to a mat3's nine entries, column by column. The reach
 * is compiled in, so the loops unroll and no tap branches. */
float gather_weight(mat3 weights, int t)
{
  int k = t + GATHER_REACH;
  return weights[k / 3][k % 3];
}

vec4 film_source(sampler2D tex, ivec2 p)
{
  ivec2 last = textureSize(tex, 0) - 1;
  vec4 sum = vec4(0.0);
  float used = 0.0;
  for (int j = -GATHER_REACH; j <= GATHER_REACH; j++) {
    float wy = gather_weight(gather_wy, j);
    for (int i = -GATHER_REACH; i <= GATHER_REACH; i++) {
      vec4 c = texelFetch(tex, clamp(p + ivec2(i, j), ivec2(0), last), 0);
      bool finite = !(any(isnan(c)) || any(isinf(c)));
      float w = finite ? wy * gather_weight(gather_wx, i) : 0.0;
      sum += w * (finite ? c : vec4(0.0));
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

#endif /* PENUMBRA_LIB_FILM_GATHER */
