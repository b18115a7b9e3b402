/* Blender's data and colour passes (engine/frame/features/passes.py), drawn apart over the
 * z-buffer the sample's lit pass left: the surface's material and lobes, no light. Each of up to
 * six targets (out_color, out_pass1 ..) writes the pass its PASS_<slot> define names
 * (passes.PASS_IDS); PASS_COUNT targets in all. */

#ifndef PASS_COUNT
#  define PASS_COUNT 1
#endif
#ifndef NODE_AOVS
#  define NODE_AOVS 0
#  define NODE_AOV_SLOTS 1
#endif

#define PASS_POSITION 1
#define PASS_OBJECT_INDEX 2
#define PASS_MATERIAL_INDEX 3
#define PASS_DIFFUSE_COLOR 4
#define PASS_GLOSSY_COLOR 5
#define PASS_TRANSMISSION_COLOR 6
#define PASS_ENVIRONMENT 7
#define PASS_DENOISING_ALBEDO 8
#define PASS_DENOISING_NORMAL 9
#define PASS_CRYPTOMATTE 10
#define PASS_UV 11
#define PASS_DRAW 12 /* which draw of the frame covers the pixel (+ 1): the Vector pass's read-back */
#define PASS_AOV_COLOR 32 /* + the AOV Output node's index in the compiled tree (NODE_AOVS): its Color */
#define PASS_AOV_VALUE 64 /* + the index: its Value */

/* What the surface shows of its colours, per lobe by weight (Cycles' Color passes: the lobe's
 * albedo, the specular layer's energy taken out of the diffuse below it). */
struct PassColors {
  vec3 diffuse, glossy, transmission;
};

PassColors pass_colors(Surface s, MaterialInputs m, vec2 ab[NODE_LOBES])
{
  PassColors c;
  c.diffuse = vec3(0.0);
  c.glossy = vec3(0.0);
  c.transmission = vec3(0.0);
#if HOLDOUT == 0
  float transmitted = 0.0;
#  if TRANSMISSION
  transmitted = transmission_share(m.transmission, m.metal);
#  endif
  for (int k = 0; k < NODE_LOBES; k++) {
    float w = max(s.lobe[k].weight, 0.0);
    vec3 albedo = max(s.lobe[k].albedo, vec3(0.0));
    if (k == 0) {
      c.transmission += w * transmitted * albedo;
      albedo *= 1.0 - transmitted;
    }
#  if NODE_SSS && ALPHA_MODE != 2
    /* The share below the surface is not the Diffuse passes' (Cycles' Subsurface passes). */
    albedo *= 1.0 - m.sss.w;
#  endif
    c.diffuse += w * albedo;
    c.glossy += w * max(s.lobe[k].f0.rgb * ab[k].x + ab[k].y, vec3(0.0));
  }
  /* The layers over the lobes, as Cycles weighs its closures: what the lobes keep under a
   * sheen and a coat, the sheen's albedo a diffuse colour, the coat's a glossy one (without
   * them a sheen over a black base had a Diffuse Color of 0 and its light left the passes). */
#  if NODE_SHEEN
  c.diffuse = c.diffuse * s.sheen.below + s.sheen.color * s.sheen.ltc.z;
  c.glossy *= s.sheen.below;
#  endif
#  if NODE_COAT
  c.diffuse *= s.coat.below;
  c.glossy = c.glossy * s.coat.below + vec3(s.coat.weight * (s.coat.f0 * s.coat.ab.x + s.coat.ab.y));
#  endif
#endif
  return c;
}

vec4 pass_value(int which, Surface s, PassColors c, vec4 tree_aov[NODE_AOV_SLOTS])
{
  if (which == PASS_POSITION) {
    return vec4(v_world, 1.0); /* relative to the frame origin, which the read-back adds */
  }
  if (which == PASS_OBJECT_INDEX) {
    return vec4(pass_ids.x, 0.0, 0.0, 1.0);
  }
  if (which == PASS_MATERIAL_INDEX) {
    return vec4(pass_ids.y, 0.0, 0.0, 1.0);
  }
  if (which == PASS_DIFFUSE_COLOR) {
    return vec4(c.diffuse, 1.0);
  }
  if (which == PASS_GLOSSY_COLOR) {
    return vec4(c.glossy, 1.0);
  }
  if (which == PASS_TRANSMISSION_COLOR) {
    return vec4(c.transmission, 1.0);
  }
  if (which == PASS_DENOISING_ALBEDO) {
    return vec4(c.diffuse + c.glossy + c.transmission, 1.0);
  }
  if (which == PASS_DENOISING_NORMAL) {
    return vec4(s.lobe[heavier_lobe(s)].N, 1.0);
  }
  if (which == PASS_CRYPTOMATTE) {
    return vec4(pass_ids.zw, pass_more.x, 1.0);
  }
  if (which == PASS_DRAW) {
    return vec4(pass_more.y, 0.0, 0.0, 1.0);
  }
  if (which == PASS_UV) {
#if HAS_UV
    return vec4(v_uv, 1.0, 1.0);
#else
    return vec4(0.0, 0.0, 0.0, 1.0);
#endif
  }
  for (int k = 0; k < NODE_AOV_SLOTS; k++) {
    if (which == PASS_AOV_COLOR + k) {
      return vec4(tree_aov[k].rgb, 1.0);
    }
    if (which == PASS_AOV_VALUE + k) {
      return vec4(tree_aov[k].a, 0.0, 0.0, 1.0);
    }
  }
  return vec4(0.0, 0.0, 0.0, 1.0); /* the Environment: no surface's */
}

void main()
{
  MaterialInputs m = material_inputs();
  bool dropped = coverage_discards(m.coverage);
#if ALPHA_MODE == 2
  /* A blended surface writes the passes where it covers at least half (Cycles' Pass Alpha
   * Threshold, 0.5). */
  dropped = dropped || m.coverage < 0.5;
#endif
  vec2 ab[NODE_LOBES];
  Surface s = surface_setup(m, ab);
  PassColors c = pass_colors(s, m, ab);
  vec4 tree_aov[NODE_AOV_SLOTS];
  for (int k = 0; k < NODE_AOV_SLOTS; k++) {
    tree_aov[k] = vec4(0.0);
  }
#if NODE_TREE && NODE_AOVS
  node_aovs(s.lobe[0].N, s.V, gl_FrontFacing, tree_aov);
#endif
  if (dropped) {
    discard;
  }
  out_color = pass_value(PASS_0, s, c, tree_aov);
#if PASS_COUNT > 1
  out_pass1 = pass_value(PASS_1, s, c, tree_aov);
#endif
#if PASS_COUNT > 2
  out_pass2 = pass_value(PASS_2, s, c, tree_aov);
#endif
#if PASS_COUNT > 3
  out_pass3 = pass_value(PASS_3, s, c, tree_aov);
#endif
#if PASS_COUNT > 4
  out_pass4 = pass_value(PASS_4, s, c, tree_aov);
#endif
#if PASS_COUNT > 5
  out_pass5 = pass_value(PASS_5, s, c, tree_aov);
#endif
}
