/* out = scale * src at (pixel - origin): a shadow tile copied into the atlas (the viewport is
 * the tile's place there), a sample added to the accumulation (the blend state adds), or the
 * accumulation resolved to its average (film_programs.SCALED_COPY); with EXTRA_COPIES the
 * sample's further accumulations too (lib/film_copies.glsl). */
void main()
{
  ivec2 p = ivec2(gl_FragCoord.xy) - origin;
  out_color = scale * film_source(src_color, p);
#if WITH_SHADOW
#  if CLAMP_SHADOW
  out_shadow = vec4(clamp(scale * film_source(src_shadow, p).r, 0.0, 1.0));
#  else
  out_shadow = vec4(scale * film_source(src_shadow, p).r);
#  endif
#endif
  film_copies(p);
}
