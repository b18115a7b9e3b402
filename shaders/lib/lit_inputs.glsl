// requires: lib/material.glsl lib/lit_surface.glsl lib/lit_terminator.glsl lib/lit_bsdf.glsl lib/subsurface.glsl
#ifndef PENUMBRA_LIB_LIT_INPUTS
#define PENUMBRA_LIB_LIT_INPUTS

/* The lit entry shaders' common start (lit.frag.glsl, lit_settle.frag.glsl, lit_debug.frag.glsl):
 * the material at this fragment and the surface with its lobes. After the compiled node tree's
 * code (programs.LIT ``entry_libs``), which material_inputs calls. With NODE_TREE it also calls
 * node_closure_resolve_lobes (shaders/nodes/shader.glsl): not a requirement here, the tree's
 * families bring it (programs.with_tree), and a variant without a tree never reads it. */

/* The material's parameters at this fragment: the MaterialData block, its image textures and
 * colour attribute, or its compiled node tree (engine/scene/nodetree.py), which gives every
 * parameter; with NODE_LOBES == 2 both lobes' and their weights (shaders/nodes/shader.glsl). */
struct MaterialInputs {
  vec4 base;
  float rough, metal, coverage;
  vec3 emission;
  vec4 spec_f0;     /* the dielectric's F0 (lobe_setup) */
  float transmission; /* Principled Transmission Weight (TRANSMISSION, lib/refraction.glsl) */
  vec3 tree_normal; /* the tree's shading normal (NODE_NORMAL) */
#if NODE_FILM
  vec4 film;        /* (weight, thickness nm, film IOR, base IOR) of a Principled Thin Film */
#endif
#if NODE_ANISO
  vec4 aniso;       /* an anisotropic specular: tangent and ln k (lib/anisotropy.glsl) */
#endif
#if NODE_SSS
  vec4 sss;         /* Burley's d per channel, the share of the diffuse below (lib/subsurface.glsl) */
  vec3 sss_exit;    /* how that share's light leaves (node_sss_walk: 1 Lambertian) */
#endif
#if NODE_SHEEN
  vec4 sheen;       /* a Principled Sheen: colour (Weight x Tint) and roughness (lib/sheen.glsl) */
  float sheen_layered; /* the share of it over the lobes (a Sheen BSDF's lies beside them) */
#endif
#if NODE_COAT
  vec4 coat;        /* (weight, roughness, IOR, 0) of a Principled coat (shaders/nodes/shader.glsl) */
  vec3 coat_tint;
  vec3 coat_normal; /* 0: the surface's interpolated normal */
#endif
#if NODE_LOBES == 2
  vec4 base_b;
  float rough_b, metal_b;
  vec4 spec_f0_b;
  vec3 tree_normal_b;
  vec2 weights;
#endif
};

MaterialInputs material_inputs()
{
  MaterialInputs m;
  m.base = material.base_color;
  m.rough = material.roughness;
  m.metal = material.metallic;
  m.coverage = material.alpha;
  m.emission = material.emission;
  m.spec_f0 = material.specular;
  m.transmission = material.transmission;
  m.tree_normal = vec3(0.0);
#if NODE_LOBES == 2
  m.base_b = m.base;
  m.rough_b = m.rough;
  m.metal_b = m.metal;
  m.spec_f0_b = m.spec_f0;
  m.tree_normal_b = vec3(0.0);
  m.weights = vec2(1.0, 0.0);
#endif
#if NODE_TREE
  vec3 V = (frame.is_ortho != 0) ? -frame.camera_forward : normalize(frame.camera_position - v_world);
  vec3 Nt = v_normal;
  float l = length(Nt);
  Nt = (l > 1e-20) ? Nt / l : vec3(0.0, 0.0, 1.0);
  bool front = dot(Nt, V) >= 0.0;
#  if NODE_LOBES == 2
  NodeClosure closure = node_tree_closure(front ? Nt : -Nt, V, front);
  node_closure_resolve_lobes(closure, m.base, m.rough, m.metal, m.spec_f0, m.coverage, m.emission, m.tree_normal,
                             m.base_b, m.rough_b, m.metal_b, m.spec_f0_b, m.tree_normal_b, m.weights);
#    if NODE_COAT
  node_coat_keep(closure);
#    endif
#    if NODE_FILM
  node_film_keep(closure);
#    endif
#    if NODE_SHEEN
  node_sheen_keep(closure);
#    endif
#    if NODE_ANISO
  node_aniso_keep(closure);
#    endif
#    if NODE_SSS
  node_sss_keep(closure);
#    endif
#  else
  node_tree(front ? Nt : -Nt, V, front, m.base, m.rough, m.metal, m.spec_f0, m.coverage, m.emission, m.tree_normal);
#  endif
#  if NODE_FILM
  m.film = node_film_params;
#  endif
#  if NODE_ANISO
  m.aniso = node_aniso_params;
#  endif
#  if NODE_SSS
  m.sss = node_sss_params;
  m.sss_exit = node_sss_exit;
#  endif
#  if NODE_SHEEN
  m.sheen = node_sheen_params;
  m.sheen_layered = node_sheen_layered;
#  endif
#  if NODE_COAT
  m.coat = node_coat_params;
  m.coat_tint = node_coat_tint;
  m.coat_normal = node_coat_normal;
#  endif
#endif
#if TEX_BASE_COLOR
  m.base *= SAMPLE_COLOR(base_color, v_uv);
#endif
#if HAS_VCOL && !NODE_TREE
  m.base *= v_color;
#endif
#if TEX_ROUGHNESS
  m.rough *= SAMPLE_VALUE(roughness, v_uv);
#endif
#if TEX_METALLIC
  m.metal *= SAMPLE_VALUE(metallic, v_uv);
#endif
#if TEX_ALPHA
  m.coverage *= SAMPLE_VALUE(alpha, v_uv);
#endif
#if TEX_EMISSION
  m.emission *= SAMPLE_COLOR(emission, v_uv).rgb;
#endif
  return m;
}

/* The surface at this fragment and its lobes from the material ``m``; ``ab``: each lobe's
 * environment BRDF (what the world's specular is weighted by). */
Surface surface_setup(MaterialInputs m, out vec2 ab[NODE_LOBES])
{
  Surface s;
  vec3 N = surface_geometry(s);
  terminator_setup(s);
#if NODE_COAT
  /* The coat over every lobe, with its own normal: the tree's, else the interpolated one (not
   * the base's normal map), as Blender's coat takes it. */
  vec3 Nc = (dot(m.coat_normal, m.coat_normal) > 0.0) ? normalize(m.coat_normal) : N;
  s.coat = coat_setup(m.coat, m.coat_tint, (dot(Nc, s.V) < 0.0) ? -Nc : Nc, s.V);
#endif
  N = shading_normal(N, m.tree_normal, s);
#if NODE_FILM
  lit_film = m.film; /* the lobes' Fresnel (lib/lit_bsdf.glsl lobe_setup, lobe_brdf) */
#endif
#if NODE_LOBES == 2
  s.lobe[0] = lobe_setup(m.base.rgb, m.rough, m.metal, m.spec_f0, N, s.V, m.weights.x, ab[0]);
  /* The second lobe: its own normal where the tree gives one, else the first lobe's. */
  s.lobe[1] = lobe_setup(m.base_b.rgb, m.rough_b, m.metal_b, m.spec_f0_b, shading_normal(N, m.tree_normal_b, s), s.V,
                         m.weights.y, ab[1]);
#else
  s.lobe[0] = lobe_setup(m.base.rgb, m.rough, m.metal, m.spec_f0, N, s.V, 1.0, ab[0]);
#endif
#if NODE_ANISO
  for (int k = 0; k < NODE_LOBES; k++) {
    lobe_anisotropy(s.lobe[k], m.aniso, s.V, ab[k]);
  }
#endif
#if NODE_SHEEN
  s.sheen = sheen_setup(m.sheen, m.sheen_layered, N, s.V); /* on the first lobe's shading normal */
#endif
#if NODE_SSS && (SUBSURFACE == 1 || LIGHT_PASS == LIGHT_PASS_SUBSURFACE)
  /* The technique's split of the diffuse (features/subsurface.py): the lit pass draws the share
   * that stays on the surface, its subsurface draw the share below it (lib/subsurface.glsl). */
  float kept = (LIGHT_PASS == LIGHT_PASS_SUBSURFACE) ? m.sss.w : 1.0 - m.sss.w;
#  if LIGHT_PASS == LIGHT_PASS_SUBSURFACE
  lit_sss = m.sss;
#  endif
  for (int k = 0; k < NODE_LOBES; k++) {
    s.lobe[k].albedo *= kept;
  }
#endif
  return s;
}

/* Whether the alpha mode drops this fragment: Hashed (EEVEE's Dithered) covers a pixel in a
 * fraction alpha of the samples (stratified over the frame's samples by frame.alpha_offset);
 * Blend drops only alpha 0 (the rest is blended by coverage, lit_outputs.glsl surface_color).
 *
 * An entry shader decides it first and discards at its end, never before the lights' and the
 * world's loops: on Mesa's llvmpipe an early discard ahead of the unrolled lights' shadow loops
 * sent LLVM's loop strength reduction (ScalarEvolution's guard reasoning over every loop the
 * discard dominates) into a compile that did not end (a hashed material lit by three sampled
 * lights with maps). The GPU's result is the same: a discarded fragment writes nothing, and
 * the lights' texture lookups stay in uniform control flow (their derivatives defined).
 * tests/blender/test_render_ends.py holds every lit entry shader to it. */
bool coverage_discards(float coverage)
{
#if ALPHA_MODE == 1
  return coverage <= fract(pixel_hash(gl_FragCoord.xy) + frame.alpha_offset);
#elif ALPHA_MODE == 2
  return coverage <= 0.0;
#else
  return false;
#endif
}

#endif /* PENUMBRA_LIB_LIT_INPUTS */
