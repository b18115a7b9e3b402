// requires:
#ifndef PENUMBRA_LIB_LIT_DEBUG
#define PENUMBRA_LIB_LIT_DEBUG

/* What the lit debug views record (engine/frame/debug_view.py; lit_debug.frag.glsl writes it):
 * globals the libraries add to as they evaluate a surface, declared only in the variants that
 * show them.
 *
 * DEBUG_LIT (programs.LitVariant ``debug``): lights evaluated (lit_lights.glsl), 1 + the cascade
 * of the first cascaded sun looked up and the map texels per screen pixel of the worst-sampled
 * light (0: no map looked up; lib/shadow_filters.glsl), the lobes' mean visibility of the world
 * with WORLD_AO (lit_world.glsl), with DEBUG_REFLECTIONS the weight of the surest hit of its
 * lobes' traced rays (SSR, lit_world.glsl: 0 none met the scene). The pixel's footprint (world-space derivatives of P) is set by
 * the entry shader, where derivatives are defined.
 * DEBUG_TERM (``debug_term``): the one term of the colour the WORLD_LIGHT (1), INDIRECT (2),
 * COAT_LIGHT (4) or SHEEN_LIGHT (5) view shows (lit_lights.glsl, lit_world.glsl). */

#if DEBUG_LIT
float debug_lights = 0.0;
float debug_cascade = 0.0;
float debug_density = 0.0;
vec3 debug_dPdx = vec3(0.0), debug_dPdy = vec3(0.0);
float debug_world_ao = 0.0;
float debug_reflected = 0.0;
#endif
#ifndef DEBUG_REFLECTIONS
#  define DEBUG_REFLECTIONS 0
#endif

#if DEBUG_TERM
vec3 debug_term = vec3(0.0);
#endif

#endif /* PENUMBRA_LIB_LIT_DEBUG */
