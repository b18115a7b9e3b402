/* One shadow tile from the scratch target into the atlas: the viewport is the tile's place in
 * the atlas, so texel (gl_FragCoord - origin) of the scratch lands there unchanged. */
void main()
{
  out_color = texelFetch(tile_color, ivec2(gl_FragCoord.xy) - origin, 0);
}
