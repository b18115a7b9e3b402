/* Where a pixel settled (features.settling.SETTLED_COPY): the pilot's value,
 * times the first sample's weight, replaces what the first sample added; elsewhere nothing
 * is written. */
void main()
{
  ivec2 p = ivec2(gl_FragCoord.xy);
  if (texelFetch(converged, p, 0).r < 0.5) {
    discard;
  }
  out_color = texelFetch(src_color, p, 0) * scale;
}
