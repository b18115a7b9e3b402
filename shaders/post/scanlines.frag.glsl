// requires:
#ifndef PENUMBRA_LIB_POST_SCANLINES
#define PENUMBRA_LIB_POST_SCANLINES

/* SCANLINES as a point layer. line_count periods over the image height (periods_per_pixel per
 * pixel), a dark band of thickness periods in each, scrolled by scroll periods. Mirrors
 * scanlines.py's scanline_darkness; rows count from the bottom. point[o]: periods per pixel,
 * thickness, intensity, scroll; point[o + 1]: line count, antialias (int bits). */

/* Dark length, in periods, inside [0, f] (f >= 0): whole periods plus the partial one. */
float scanlines_dark_measure(float f, float thickness)
{
  float n = floor(f);
  return n * thickness + min(f - n, thickness);
}

/* fract(num / den * line_count - scroll) for integer num, den: the integer part of the
 * position is dropped exactly in integers (num * (count mod den) mod den), so the phase keeps
 * float32 precision however many lines lie below the pixel. Exact for den < 65536. */
float scanlines_phase(uint num, uint den, int line_count, float scroll)
{
  uint r = (num * (uint(line_count) % den)) % den;
  float u = float(r) / float(den) - scroll;
  return u - floor(u);
}

vec4 scanlines_point(vec4 c, int o)
{
  float periods_per_pixel = point[o].v.x;
  float thickness = point[o].v.y;
  float intensity = point[o].v.z;
  float scroll = point[o].v.w;
  int line_count = floatBitsToInt(point[o + 1].v.x);
  bool antialias = floatBitsToInt(point[o + 1].v.y) != 0;
  uint row = uint(gl_FragCoord.y);
  uint height = uint(target_size.y);
  float dark;
  if (antialias) {
    /* Box filter over the pixel's height: the covered fraction of [row, row + 1]. */
    float w = periods_per_pixel;
    float f0 = scanlines_phase(row, height, line_count, scroll);
    dark = (scanlines_dark_measure(f0 + w, thickness) - scanlines_dark_measure(f0, thickness)) / w;
  }
  else {
    /* The pixel centre, row + 1/2 = (2 row + 1) / 2. */
    dark = (scanlines_phase(2u * row + 1u, 2u * height, line_count, scroll) < thickness) ? 1.0 : 0.0;
  }
  return vec4(c.rgb * (1.0 - intensity * dark), c.a);
}

#endif /* PENUMBRA_LIB_POST_SCANLINES */
