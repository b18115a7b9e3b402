/* The world ratio's three per-sample targets (the SH light diffuse and specular, the sums)
 * times ``scale`` into their accumulations in one pass (features.world_ratio.COPY; the blend
 * state adds); WITH_MASK: not where the pixel converged (adaptive sampling). */
void main()
{
  ivec2 p = ivec2(gl_FragCoord.xy);
#if WITH_MASK
  if (texelFetch(converged, p, 0).r > 0.5) {
    discard;
  }
#endif
  out_world_diffuse = scale * film_source(world_diffuse, p);
  out_world_specular = scale * film_source(world_specular, p);
  out_world_sums = scale * film_source(world_sums, p);
}
