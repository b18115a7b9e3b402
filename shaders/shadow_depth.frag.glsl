/* Linear depth along the light's view axis, normalised to the tile's [near, far]: written as
 * the fragment's depth for FLOAT32 maps (the depth buffer is the map), else as colour in the
 * selected encoding (half float, or the seeds' RGBA8 packing). A caster with alpha
 * (ALPHA_CUTOUT) covers a texel in a fraction alpha of the samples, with the lit pass's
 * stratified hash: over a frame its shadow lets 1 - alpha of the light through, as Cycles'
 * transparent shadows; an alpha texture of 0 and 1 casts its exact cut-out in every sample.
 * CAMERA_DEPTH (the world's ambient occlusion prepass): the camera's view depth as colour, with
 * the lit pass's hash, so a dithered surface covers the same pixels as in the lit pass. */
void main()
{
#if INSTANCED
  ShadowTile tile = tiles[v_tile]; /* this instance's tile (shadow_depth.vert.glsl) */
#endif
#if RSM_MATERIAL
  vec3 rsm_base = material.base_color.rgb;
  float rsm_metal = material.metallic;
#endif
#if ALPHA_CUTOUT
  float coverage = material.alpha;
#  if NODE_TREE
  {
    /* The compiled node tree's alpha (engine/scene/nodetree.py), seen from the light. */
    vec3 V = normalize(vec3(tile.view[0][2], tile.view[1][2], tile.view[2][2]));
    float l = length(v_normal);
    vec3 Nt = (l > 1e-20) ? v_normal / l : V;
    bool front = dot(Nt, V) >= 0.0;
    vec4 base = vec4(0.8, 0.8, 0.8, 1.0);
    float rough = 0.5, metal = 0.0;
    vec4 spec = vec4(0.04);
    vec3 emission = vec3(0.0), normal = vec3(0.0);
    node_tree(front ? Nt : -Nt, V, front, base, rough, metal, spec, coverage, emission, normal);
#    if RSM_MATERIAL
    rsm_base = base.rgb;
    rsm_metal = metal;
#    endif
  }
#  endif
#  if TEX_ALPHA
  coverage *= SAMPLE_VALUE(alpha, v_uv);
#  endif
  if (coverage <= fract(pixel_hash(gl_FragCoord.xy) + alpha_offset)) {
    discard;
  }
#endif
#if RSM_OUTPUT
  {
    /* Reflective shadow maps (lib/indirect_rsm.glsl): the diffuse albedo (base colour times
     * 1 - metallic, bounded to half-float range) and the normal on the side the light sees
     * (meshes are two-sided); hair strips (no RSM_MATERIAL) reflect nothing. */
    vec3 toward = v_rsm_to_light;
    float nl = length(v_rsm_normal);
    vec3 n = (nl > 1e-20) ? v_rsm_normal / nl : normalize(toward);
    n = (dot(n, toward) < 0.0) ? -n : n;
#  if RSM_MATERIAL
    vec3 albedo = clamp(rsm_base, vec3(0.0), vec3(1e4)) * (1.0 - clamp(rsm_metal, 0.0, 1.0));
    albedo = (any(isnan(albedo))) ? vec3(0.0) : albedo;
#  else
    vec3 albedo = vec3(0.0);
#  endif
    out_rsm_flux = vec4(albedo, 1.0);
    out_rsm_normal = vec4(n, 0.0);
  }
#endif
#if CAMERA_DEPTH
  out_depth = vec4(v_distance); /* the view depth itself, in a float target (world/occlusion.py) */
#elif DEPTH_FORMAT == DEPTH_FLOAT32
#  if !RASTER_DEPTH /* orthographic tiles rasterise this depth already (frame/programs.py) */
  gl_FragDepth = clamp((v_distance - tile.near) / (tile.far - tile.near), 0.0, 1.0);
#  endif
#else
  float d = clamp((v_distance - tile.near) / (tile.far - tile.near), 0.0, 1.0);
  /* The scratch z-buffer tests this same depth: the rasterised one is bent across a caster
   * that crosses the near plane (pancaked per vertex, shadow_depth.vert). */
  gl_FragDepth = d;
  out_depth = encode_depth(d);
#endif
}
