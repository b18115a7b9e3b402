/* out = scale * src where the pixel has not converged (adaptive sampling): a sample added to
 * the accumulation (the blend state adds), to the every-other-sample accumulation the error
 * estimate compares with, and to each pixel's own weight (film_programs.MASKED_COPY). A converged
 * pixel keeps what it has; with EXTRA_COPIES the sample's further accumulations too, through
 * the same mask (lib/film_copies.glsl). */
void main()
{
  ivec2 p = ivec2(gl_FragCoord.xy);
  if (texelFetch(converged, p, 0).r > 0.5) {
    discard;
  }
  out_color = scale * film_source(src_color, p);
#if WITH_SHADOW
  out_shadow = vec4(scale * film_source(src_shadow, p).r);
#endif
#if WITH_WEIGHT
  out_weight = vec4(scale, 1.0, 0.0, 0.0); /* its weight, and one sample more */
#endif
  film_copies(p);
}
