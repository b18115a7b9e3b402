// requires: lib/common.glsl lib/world_env.glsl lib/ssr.glsl lib/lit_surface.glsl lib/lit_world.glsl
#ifndef PENUMBRA_LIB_REFRACTION
#define PENUMBRA_LIB_REFRACTION

/* What a transmissive surface shows through it (TRANSMISSION: a Principled BSDF's
 * Transmission Weight, a Glass BSDF; engine/frame/features/refraction.py). The share of the
 * dielectric's diffuse that transmits (Transmission Weight, none of a metal's) is instead the
 * light that comes through the surface: the direction ``V`` refracted by a GGX microfacet
 * normal drawn anew each sample (Walter et al. 2007; the shading normal for roughness 0) at
 * the material's IOR (Snell's law: GLSL refract), through the object and out of it again, then
 * traced in screen space (lib/ssr.glsl ssr_march) against the camera depth of what is not
 * transmissive (refr_depth) and read from this sample's colour of the opaque surfaces
 * (refr_behind); a ray that meets nothing on the screen takes the world's light along its
 * direction. It is weighted by what the specular layer does not reflect (1 - the environment
 * BRDF) and tinted by the base colour, as Cycles' glass and Principled transmission are.
 *
 * Out of the object again as EEVEE's Thickness Mode models it, with its default thickness
 * ``object_thickness`` (the object's smallest dimension, per draw): SPHERE, a sphere of that
 * diameter touching the surface where the ray enters (exact for a ball), the ray refracted
 * again where it leaves it; THICKNESS_SLAB, a slab of that thickness (a pane, a cube's face),
 * leaving through a parallel face. A flat object (thickness 0) has one interface. No caustics
 * (light through glass onto what is behind it: its shadow is opaque, as Cycles' with caustics
 * off), no dispersion, nothing seen through two transmissive surfaces. Without the REFRACTION
 * part (a frame that plans none) the ray takes the world's light alone. frame.refr_params: (the
 * longest ray in world units, the thickness taken for a surface as a fraction of its depth,
 * 0, 0). */

#if TRANSMISSION

/* The share of the surface that transmits: its Transmission Weight, of the dielectric part. */
float transmission_share(float transmission, float metal)
{
  return clamp(transmission, 0.0, 1.0) * (1.0 - clamp(metal, 0.0, 1.0));
}

/* The world's light along ``T`` for a lobe of roughness ``rough`` (lib/lit_world.glsl). */
vec3 refraction_world(vec3 T, float rough)
{
  return world_glossy_radiance(T, rough);
}

/* The light that comes through surface ``s`` of base colour ``base`` (lobe 0: the dielectric;
 * ``ab`` its environment BRDF), per unit of its transmitting share. */
vec3 surface_refraction(Surface s, vec3 base, vec2 ab)
{
  Lobe b = s.lobe[0];
  vec3 V = s.V, N = b.N;
  float rough = b.rough;
  float eta = 1.0 / max(material.ior, 1e-3);
  vec3 xi = ssr_random(NODE_LOBES + 5);
  vec3 H = (rough > 0.0) ? ggx_half_vector(xi.xy, rough * rough, N) : N;
  if (!(dot(H, V) > 0.0)) {
    H = N;
  }
  vec3 T = refract(-V, H, eta);
  if (!(dot(T, N) < 0.0)) {
    /* Total internal reflection (an IOR under 1) or a microfacet that sends it above: through
     * the shading normal, else straight on. */
    T = refract(-V, N, eta);
    T = (dot(T, N) < 0.0) ? T : -V;
  }
  T = normalize(T);
  vec3 P = s.P;
  float thickness = max(object_thickness, 0.0);
  if (thickness > 0.0) {
#  if THICKNESS_SLAB
    /* Through a slab: out of the parallel face (its outward normal -N), bent back as it came. */
    vec3 Nx = -N;
    P += T * (thickness / max(-dot(T, N), 0.05));
#  else
    /* Through a sphere of diameter ``thickness`` touching the surface: out at the chord's other
     * end (its outward normal Nx). */
    float radius = 0.5 * thickness;
    vec3 C = s.P - N * radius;
    P = s.P + T * (-2.0 * radius * dot(T, N));
    vec3 Nx = normalize(P - C);
#  endif
    vec3 out_dir = refract(T, -Nx, max(material.ior, 1e-3));
    /* Totally reflected inside: it leaves as if mirrored once (one more bounce, not traced). */
    T = normalize((dot(out_dir, out_dir) > 0.0) ? out_dir : reflect(T, -Nx));
  }
  vec3 world = refraction_world(T, rough);
  vec3 through = world;
#  if REFRACTION
  vec2 hit;
  float w = ssr_march(
      refr_depth, 0, frame.view, frame.view_proj, frame.refr_params.x, frame.refr_params.y, false, P, N, T, xi.z, hit);
  bool ok = false;
  vec3 behind = (w > 0.0) ? ssr_fetch(refr_behind, hit, ok) : vec3(0.0);
  if (ok) {
    through = mix(world, behind, w);
  }
#  endif
  vec3 dfg = b.f0.rgb * ab.x + ab.y;
  return max(base, vec3(0.0)) * clamp(1.0 - dfg, 0.0, 1.0) * through;
}
#endif

#endif /* PENUMBRA_LIB_REFRACTION */
