/* PIXELATE, one pass selected by PIXELATE_PASS, one of pixelate.py's PASS_* values:
 * CENTER:  each pixel takes its cell's centre pixel of source_tex.
 * ROWS:    pixel (i, y) of a compact grid = mean of cell column i's pixels in row y of
 *            input_tex (the source); pixels beyond the grid write 0.
 * COLUMNS: pixel (i, j) = mean of rows of cell j in input_tex (the ROWS result).
 * EXPAND:  each pixel takes its cell's value from input_tex (the COLUMNS result).
 * Cells are anchored at pixel (0, 0); partial edge cells use the pixels that exist. */
void main()
{
  ivec2 size = textureSize(source_tex, 0);
  ivec2 p = ivec2(gl_FragCoord.xy);
  ivec2 cells = (size + cell_size - 1) / cell_size;
#if PIXELATE_PASS == PASS_CENTER
  ivec2 origin = (p / cell_size) * cell_size;
  ivec2 n = min(ivec2(cell_size), size - origin);
  out_color = post_mix(sanitize(texelFetch(source_tex, origin + n / 2, 0)));
#elif PIXELATE_PASS == PASS_ROWS
  if (p.x >= cells.x) {
    out_color = vec4(0.0);
    return;
  }
  int x0 = p.x * cell_size;
  int x1 = min(x0 + cell_size, size.x);
  vec4 acc = vec4(0.0);
  for (int x = x0; x < x1; x++) {
    acc += sanitize(texelFetch(input_tex, ivec2(x, p.y), 0));
  }
  out_color = acc / float(x1 - x0);
#elif PIXELATE_PASS == PASS_COLUMNS
  if (p.x >= cells.x || p.y >= cells.y) {
    out_color = vec4(0.0);
    return;
  }
  int y0 = p.y * cell_size;
  int y1 = min(y0 + cell_size, size.y);
  vec4 acc = vec4(0.0);
  for (int y = y0; y < y1; y++) {
    acc += texelFetch(input_tex, ivec2(p.x, y), 0);
  }
  out_color = acc / float(y1 - y0);
#else
  out_color = post_mix(texelFetch(input_tex, p / cell_size, 0));
#endif
}
