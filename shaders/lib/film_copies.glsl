// requires: lib/film_gather.glsl
#ifndef PENUMBRA_LIB_FILM_COPIES
#define PENUMBRA_LIB_FILM_COPIES

/* A sample's further accumulations added in the pass that adds its colour (film.Film.accumulate,
 * film_programs.with_copies): EXTRA_COPIES sources src_copy0 .. times ``scale`` into out_copy0 ..
 * (the blend state adds), each exactly as a pass of its own would add it: the Emission pass,
 * the every-other-sample accumulation, a technique's targets (the world ratio's sums), the
 * render passes' means. Blender's gpu module binds six colour targets, so at most five ride
 * along with the colour; a pass of copies alone takes six. */

#ifndef EXTRA_COPIES
#  define EXTRA_COPIES 0
#endif

void film_copies(ivec2 p)
{
#if EXTRA_COPIES > 0
  out_copy0 = scale * film_source(src_copy0, p);
#endif
#if EXTRA_COPIES > 1
  out_copy1 = scale * film_source(src_copy1, p);
#endif
#if EXTRA_COPIES > 2
  out_copy2 = scale * film_source(src_copy2, p);
#endif
#if EXTRA_COPIES > 3
  out_copy3 = scale * film_source(src_copy3, p);
#endif
#if EXTRA_COPIES > 4
  out_copy4 = scale * film_source(src_copy4, p);
#endif
}

#endif /* PENUMBRA_LIB_FILM_COPIES */
