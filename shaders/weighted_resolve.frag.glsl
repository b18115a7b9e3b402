/* The accumulation divided by each pixel's own weight: once adaptive sampling stopped some
 * pixels, pixels hold different numbers of samples (film_programs.WEIGHTED_RESOLVE). */
void main()
{
  ivec2 p = ivec2(gl_FragCoord.xy);
  float w = texelFetch(weight, p, 0).r;
  float inverse = (w > 0.0) ? 1.0 / w : 0.0;
  out_color = inverse * texelFetch(src_color, p, 0);
#if WITH_SHADOW
  /* sum(w v) / sum(w) of visibilities in [0, 1]: in [0, 1] but for rounding. */
  out_shadow = vec4(clamp(inverse * texelFetch(src_shadow, p, 0).r, 0.0, 1.0));
#endif
}
