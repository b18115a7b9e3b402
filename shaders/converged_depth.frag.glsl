/* Before a sample's lit pass: the nearest depth (0) where the pixel has converged, so every
 * surface fails the depth test there and is not shaded (film_programs.CONVERGED_DEPTH); elsewhere
 * nothing is written. Drawn with colour writes masked off. A gathering film (``reach`` > 0)
 * keeps shading a converged pixel while a pixel within ``reach`` of it has not converged:
 * that pixel gathers its sample (lib/film_gather.glsl). */
void main()
{
  ivec2 p = ivec2(gl_FragCoord.xy);
  ivec2 last = textureSize(converged, 0) - 1;
  for (int y = -reach; y <= reach; y++) {
    for (int x = -reach; x <= reach; x++) {
      if (texelFetch(converged, clamp(p + ivec2(x, y), ivec2(0), last), 0).r < 0.5) {
        discard;
      }
    }
  }
  gl_FragDepth = 0.0;
  out_color = vec4(0.0);
}
