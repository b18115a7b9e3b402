// requires: lib/lit_surface.glsl
#ifndef PENUMBRA_LIB_LIT_TERMINATOR
#define PENUMBRA_LIB_LIT_TERMINATOR

/* Object > Shading > Shadow Terminator (engine/scene/terminator.py), per object variant:
 * TERMINATOR_OFFSET lifts each light's shadow point towards the smooth surface the vertex
 * normals imply (Cycles' Geometry Offset), TERMINATOR_NORMAL moves it along the normal (EEVEE's
 * Normal Offset), TERMINATOR_SHADING raises the cosine term's frequency (Cycles' Shading
 * Offset). */

#if TERMINATOR_OFFSET
/* Cycles' smooth-surface offset at this fragment (engine/scene/terminator.py smooth_offset):
 * the interpolated normal times the height of the parabola through the triangle's vertex
 * normals, bounded by the vertices' tangent planes (affine over the triangle, interpolated
 * exactly from the corners). ``Nv``: the facet's normal towards the viewer; seen from
 * behind its normals the offset goes the other way. */
vec3 smooth_surface_offset(vec3 Nv)
{
  float u = v_tbary.x, v = v_tbary.y;
  float a = v_tabc.x, b = v_tabc.y, c = v_tabc.z;
  float h = a * u * (u - 1.0) + (a + b + c) * u * v + b * v * (v - 1.0);
  vec3 n = v_tnormal;
  if (dot(n, Nv) > 0.0) {
    vec3 e = max(v_tfront, vec3(0.0));
    h = max(min(min(e.x, e.y), e.z), 0.5 * h);
  }
  else {
    vec3 e = max(v_tback, vec3(0.0));
    h = min(-min(min(e.x, e.y), e.z), 0.5 * h);
  }
  vec3 o = n * h;
  return (any(isnan(o)) || any(isinf(o))) ? vec3(0.0) : o;
}

/* How much of the offset light direction L gets: all of it where the smooth normal (NL) and
 * the facet (NgL) are at a grazing angle to it, none beyond the Geometry Offset. */
float smooth_offset_amount(float NL, float NgL)
{
  float cutoff = terminator_geometry_offset;
  return (NL < cutoff) ? clamp(2.0 - (NgL + NL) / cutoff, 0.0, 1.0) : clamp(1.0 - NgL / cutoff, 0.0, 1.0);
}
#endif

/* The surface's smooth-surface offset, once a fragment (TERMINATOR_OFFSET; nothing else). */
void terminator_setup(inout Surface s)
{
#if TERMINATOR_OFFSET
  s.smooth_offset = smooth_surface_offset(s.Nv);
#endif
}

/* The cosine term; Cycles' Shading Offset replaces cos(theta) by max(cos(f theta), 0). */
float cosine_term(float NdotL)
{
#if TERMINATOR_SHADING
  return max(cos(acos(min(NdotL, 1.0)) * terminator_shading_frequency), 0.0);
#else
  return NdotL;
#endif
}

/* Where the shadow of light from ``to_light`` is looked up: the shading point, moved towards
 * the smooth surface (TERMINATOR_OFFSET) or along the normal (TERMINATOR_NORMAL). */
vec3 shadow_point(Surface s, vec3 to_light, float NgdotL)
{
  vec3 P = s.P;
#if TERMINATOR_OFFSET
  P += s.smooth_offset * smooth_offset_amount(NgdotL, dot(s.Nv, to_light));
#endif
#if TERMINATOR_NORMAL
  /* EEVEE: along the normal, by Normal Offset x saturate(1 - N.L / Geometry Offset). */
  P += s.Ng * (clamp(1.0 - NgdotL / terminator_geometry_offset, 0.0, 1.0) * terminator_normal_offset);
#endif
  return P;
}

/* On a closed surface seen from outside, a facet turned away from the light (its own plane,
 * not the smoothed normal) is in the surface's own shadow: the ray to the light enters the
 * solid. Decided exactly, with no bias, where the map's depths are nearly equal (lights with
 * jittered maps, whose biases shrink with the samples; one-sample frames as before). Not where
 * Shadow Terminator's Geometry Offset moves the point off its facet: the map decides there, as
 * Cycles' offset ray does. */
bool facet_turned(Surface s, LightData L, vec3 to_light)
{
#if TERMINATOR_OFFSET
  return false;
#else
  return solid != 0 && L.jittered != 0 && dot(s.Nf, to_light) <= 0.0;
#endif
}

#endif /* PENUMBRA_LIB_LIT_TERMINATOR */
