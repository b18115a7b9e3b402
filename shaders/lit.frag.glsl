/* The lit pass (engine/frame/lit_pass.py): the surface's material, its lobes, the world's light
 * and every light's, with their shadows. By concern, in the libraries the program lists
 * (engine/frame/programs.py LIT), in this order:
 *   lib/lit_surface.glsl     the Surface and its lobes; point, view, normals, normal maps, hair
 *   lib/lit_terminator.glsl  Shadow Terminator: where a light's shadow is looked up, the cosine
 *   lib/lit_bsdf.glsl        the Principled layering: lobe_setup, lobe_brdf, env_brdf
 *   lib/lit_world.glsl       the world's SH light, its occlusion (WORLD_AO) and ratio (WORLD_RATIO)
 *   lib/lit_settle.glsl      the settle test's flags (SETTLE_TEST)
 *   lib/lit_lights.glsl      add_light (one shadow lookup, every lobe) and lights_on (the loops)
 * The material comes from the MaterialData block and, per variant (programs.material_defines),
 * image textures, a colour attribute, a normal map, the alpha mode, or a compiled node tree.
 *
 * Variants (programs.LitVariant and the material's defines), what each writes:
 *   default        colour (+ Shadow, Normal and Depth with AUX_OUTPUTS, Emission with
 *                  EMISSION_OUTPUT; the ratio's targets with WORLD_RATIO_OUT)
 *   EMISSION_ONLY  the Emission pass alone, over the z-buffer the lit pass left
 *   DEBUG_LIT      a lit debug view's values (lights evaluated, cascade, texel density; the
 *                  world's visibility with WORLD_AO) instead of colour
 *   DEBUG_TERM     one term of the colour: 1 the world's light, 2 the diffuse bounce
 *   SETTLE_TEST    the settle test's flags (engine/frame/settle.py) instead of colour */

/* The material's parameters at this fragment: the MaterialData block, its image textures and
 * colour attribute, or its compiled node tree (engine/scene/nodetree.py), which gives every
 * parameter; with NODE_LOBES == 2 both lobes' and their weights (shaders/nodes/shader.glsl). */
struct MaterialInputs {
  vec4 base;
  float rough, metal, coverage;
  vec3 emission;
  vec4 spec_f0;     /* the dielectric's F0 (lobe_setup) */
  vec3 tree_normal; /* the tree's shading normal (NODE_NORMAL) */
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
  node_closure_resolve_lobes(node_tree_closure(front ? Nt : -Nt, V, front), m.base, m.rough, m.metal, m.spec_f0,
                             m.coverage, m.emission, m.tree_normal, m.base_b, m.rough_b, m.metal_b, m.spec_f0_b,
                             m.tree_normal_b, m.weights);
#  else
  node_tree(front ? Nt : -Nt, V, front, m.base, m.rough, m.metal, m.spec_f0, m.coverage, m.emission, m.tree_normal);
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
  N = shading_normal(N, m.tree_normal, s);
#if NODE_LOBES == 2
  s.lobe[0] = lobe_setup(m.base.rgb, m.rough, m.metal, m.spec_f0, N, s.V, m.weights.x, ab[0]);
  /* The second lobe: its own normal where the tree gives one, else the first lobe's. */
  s.lobe[1] = lobe_setup(m.base_b.rgb, m.rough_b, m.metal_b, m.spec_f0_b, shading_normal(N, m.tree_normal_b, s), s.V,
                         m.weights.y, ab[1]);
#else
  s.lobe[0] = lobe_setup(m.base.rgb, m.rough, m.metal, m.spec_f0, N, s.V, 1.0, ab[0]);
#endif
  return s;
}

void main()
{
  MaterialInputs m = material_inputs();
  float coverage = m.coverage;
  vec3 emission = m.emission;
#if ALPHA_MODE == 1 && SETTLE_TEST
  if (coverage <= 0.0) {
    discard; /* never drawn; where it covers some samples, it marks the pixel unsettled */
  }
#elif ALPHA_MODE == 1
  /* Hashed (EEVEE's Dithered): the surface covers a pixel in a fraction alpha of the samples
   * (stratified over the frame's samples by frame.alpha_offset). */
  if (coverage <= fract(pixel_hash(gl_FragCoord.xy) + frame.alpha_offset)) {
    discard;
  }
#elif ALPHA_MODE == 2
  if (coverage <= 0.0) {
    discard;
  }
#endif
#if EMISSION_ONLY
  /* The Emission pass drawn apart, over the z-buffer the lit pass left (a frame whose other
   * targets leave its own no room: lit_pass.py). */
#  if HOLDOUT
  out_color = vec4(0.0);
#  else
  out_color = vec4(emission, 1.0);
#  endif
  return;
#endif

  vec2 ab[NODE_LOBES];
  Surface s = surface_setup(m, ab);

  /* --- light: the world's, the lights', the bounce --- */
  vec3 color = surface_world_light(s, ab);
  vec3 world_term = color; /* the world's light, unshadowed (the settle test, DEBUG_TERM 1) */
  float arriving = 0.0, unshadowed = 0.0;
#if DEBUG_TERM == 1
  debug_term += world_term;
#endif
#if DEBUG_LIT
  debug_dPdx = dFdx(s.P);
  debug_dPdy = dFdy(s.P);
#endif
  lights_on(s, color, arriving, unshadowed);
#if INDIRECT_RSM && !SETTLE_TEST && !DEBUG_LIT
  {
    /* One diffuse bounce from the lights' reflective shadow maps (lib/indirect_rsm.glsl),
     * reflected by the diffuse lobe(s). */
    vec3 albedo = vec3(0.0);
    for (int k = 0; k < NODE_LOBES; k++) {
      albedo += s.lobe[k].weight * s.lobe[k].albedo;
    }
    vec3 bounced = indirect_rsm(s.P, s.lobe[0].N, v_view_depth) / M_PI * albedo;
    color += bounced;
#  if DEBUG_TERM == 2
    debug_term += bounced;
#  endif
  }
#endif
#if WORLD_RATIO && WORLD_RATIO_OUT != 1
  /* No film sums for this surface (a blended one): its own ratio within this sample. */
  color = world_ratio_apply(vec4(color, 1.0), world_d, world_s, world_sums).rgb;
#  if DEBUG_TERM == 1
  debug_term = world_ratio_apply(vec4(debug_term, 1.0), world_d, world_s, world_sums).rgb;
#  endif
#endif
  color += emission;

  /* --- what the variant writes --- */
#if HOLDOUT
  out_color = vec4(0.0); /* Object > Visibility > Holdout: a hole in the film */
#elif ALPHA_MODE == 2
  float a = clamp(coverage, 0.0, 1.0);
  out_color = vec4(color * a, a); /* premultiplied, blended over what is behind */
#else
  out_color = vec4(color, 1.0);
#endif
#if DEBUG_TERM && !HOLDOUT
  out_color = vec4(debug_term, 1.0); /* the WORLD_LIGHT or INDIRECT debug view */
#endif
#if DEBUG_LIT && WORLD_AO
  out_color = vec4(debug_world_ao, 0.0, 0.0, 1.0); /* the WORLD_AO debug view: the world's visibility */
#elif DEBUG_LIT
  out_color = vec4(debug_lights, debug_cascade, debug_density, 1.0); /* a lit debug view's values */
#endif
#if SETTLE_TEST
  out_color = settle_flags(world_term, coverage);
#endif
#if AUX_OUTPUTS
  /* A ratio of weighted sums lies in [0, 1] but for rounding (a division need not be
   * correctly rounded: w / w may be 1.0000001). */
  out_shadow = (unshadowed > 0.0) ? clamp(arriving / unshadowed, 0.0, 1.0) : 1.0;
  /* The heavier lobe's world-space shading normal, facing the camera (Normal pass); w: view
   * depth (Depth pass). */
  out_normal = vec4(s.lobe[heavier_lobe(s)].N, v_view_depth);
#endif
#if EMISSION_OUTPUT
#  if HOLDOUT
  out_emission = vec4(0.0);
#  else
  out_emission = vec4(emission, 1.0); /* the Emission pass: what the surface emits */
#  endif
#endif
#if WORLD_RATIO_OUT == 1
  /* The SH light by lobe that the colour carries, and the ratio's sums (none in a hole, nor
   * in the INDIRECT view's image, which has no world light, nor in a lit debug view's). */
#  if HOLDOUT || DEBUG_TERM == 2 || DEBUG_LIT || !WORLD_RATIO
  out_world_diffuse = vec4(0.0, 0.0, 0.0, 1.0);
  out_world_specular = vec4(0.0, 0.0, 0.0, 1.0);
  out_world_sums = vec4(0.0);
#  else
  out_world_diffuse = vec4(world_d, 1.0);
  out_world_specular = vec4(world_s, 1.0);
  out_world_sums = world_sums;
#  endif
#elif WORLD_RATIO_OUT == 2
  /* Blended over the surface behind: its unshadowed world light is seen through 1 - alpha. */
  out_world_diffuse = vec4(0.0, 0.0, 0.0, out_color.a);
  out_world_specular = vec4(0.0, 0.0, 0.0, out_color.a);
#endif
#if COUNT_SHADED
  out_shaded = 1.0; /* this pixel was shaded in this sample (programs.LIT_COLOR_COUNTED) */
#endif
}
