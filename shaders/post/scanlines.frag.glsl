/* line_count periods over the image height (periods_per_pixel per pixel), a dark band of
 * thickness periods in each, scrolled by scroll periods. Mirrors scanlines.py's
 * scanline_darkness; rows count from the bottom. */

/* Dark length, in periods, inside [0, f] (f >= 0): whole periods plus the partial one. */
float dark_measure(float f)
{
  float n = floor(f);
  return n * thickness + min(f - n, thickness);
}

/* fract(num / den * line_count - scroll) for integer num, den: the integer part of the
 * position is dropped exactly in integers (num * (count mod den) mod den), so the phase keeps
 * float32 precision however many lines lie below the pixel. Exact for den < 65536. */
float phase(uint num, uint den)
{
  uint r = (num * (uint(line_count) % den)) % den;
  float u = float(r) / float(den) - scroll;
  return u - floor(u);
}

void main()
{
  vec4 c = post_source();
  uint row = uint(gl_FragCoord.y);
  uint height = uint(target_size.y);
  float dark;
  if (antialias != 0) {
    /* Box filter over the pixel's height: the covered fraction of [row, row + 1]. */
    float w = periods_per_pixel;
    float f0 = phase(row, height);
    dark = (dark_measure(f0 + w) - dark_measure(f0)) / w;
  }
  else {
    /* The pixel centre, row + 1/2 = (2 row + 1) / 2. */
    dark = (phase(2u * row + 1u, 2u * height) < thickness) ? 1.0 : 0.0;
  }
  out_color = post_mix(vec4(c.rgb * (1.0 - intensity * dark), c.a));
}
