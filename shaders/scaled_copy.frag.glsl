/* out = scale * src at (pixel - origin): a shadow tile copied into the atlas (the viewport is
 * the tile's place there), a sample added to the accumulation (the blend state adds), or the
 * accumulation resolved to its average (film_programs.SCALED_COPY). */
void main()
{
  ivec2 p = ivec2(gl_FragCoord.xy) - origin;
  out_color = scale * texelFetch(src_color, p, 0);
#if WITH_SHADOW
#  if CLAMP_SHADOW
  out_shadow = vec4(clamp(scale * texelFetch(src_shadow, p, 0).r, 0.0, 1.0));
#  else
  out_shadow = vec4(scale * texelFetch(src_shadow, p, 0).r);
#  endif
#endif
}
