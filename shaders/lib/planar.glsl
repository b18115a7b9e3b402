// requires: lib/common.glsl lib/ssr.glsl
#ifndef PENUMBRA_LIB_PLANAR
#define PENUMBRA_LIB_PLANAR

/* A Plane Light Probe's reflection (engine/frame/features/planar.py): each sample the lit pass
 * draws the scene mirrored about the probe's plane (planar_color, with the view depth of the
 * mirrored camera in planar_depth's w, 1e10 where nothing was drawn), and a traced lobe of a
 * surface in the probe's influence marches its ray (ssr_march) through that capture instead of
 * the screen: a perfect mirror's ray, seen from the mirrored camera, is the pixel's own, so a
 * mirror floor reads what the mirrored camera saw there, whatever the screen holds.
 * frame.planar_view and planar_view_proj: the mirrored camera (this sample's pixel offset
 * included, so the capture's pixels are the sample's); planar_influence: positions relative to
 * the origin into the probe's influence box (EEVEE's: -1..1 inside, its Z the Influence
 * Distance along the normal); planar_plane: (normal, d) of the mirror; planar_params: (the
 * longest ray, a surface's thickness as a fraction of its depth, 0, 0). */

#if PLANAR
/* How much a surface at ``P`` of normal ``N`` takes the probe's reflection: 1 inside the
 * influence box facing the mirror's side, fading to 0 as the normal turns along the plane. */
float planar_weight(vec3 P, vec3 N)
{
  vec3 local = (frame.planar_influence * vec4(P, 1.0)).xyz;
  if (any(greaterThan(abs(local), vec3(1.0)))) {
    return 0.0;
  }
  return smoothstep(0.0, 0.25, dot(N, frame.planar_plane.xyz));
}

/* The capture's weight for the ray from ``P`` (normal ``N``) along ``L`` and ``radiance``
 * where it meets something there (0: outside the influence, or no hit). */
float planar_trace(vec3 P, vec3 N, vec3 L, float jitter, out vec3 radiance)
{
  radiance = vec3(0.0);
  float influence = planar_weight(P, N);
  if (!(influence > 0.0)) {
    return 0.0;
  }
  vec2 hit;
  float w = ssr_march(planar_depth,
                      3,
                      frame.planar_view,
                      frame.planar_view_proj,
                      frame.planar_params.x,
                      frame.planar_params.y,
                      false,
                      P,
                      N,
                      L,
                      jitter,
                      hit);
  bool ok = false;
  radiance = (w > 0.0) ? ssr_fetch(planar_color, hit, ok) : vec3(0.0);
  return ok ? influence * w : 0.0;
}
#endif

#endif /* PENUMBRA_LIB_PLANAR */
