/* Before a sample's lit pass: the nearest depth (0) where the pixel has converged, so every
 * surface fails the depth test there and is not shaded (film_programs.CONVERGED_DEPTH); elsewhere
 * nothing is written. Drawn with colour writes masked off. */
void main()
{
  if (texelFetch(converged, ivec2(gl_FragCoord.xy), 0).r < 0.5) {
    discard;
  }
  gl_FragDepth = 0.0;
  out_color = vec4(0.0);
}
