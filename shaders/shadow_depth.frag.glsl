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
  }
#  endif
#  if TEX_ALPHA
  coverage *= SAMPLE_VALUE(alpha, v_uv);
#  endif
  if (coverage <= fract(pixel_hash(gl_FragCoord.xy) + alpha_offset)) {
    discard;
  }
#endif
#if CAMERA_DEPTH
  out_depth = vec4(v_distance); /* the view depth itself, in a float target (world_ao.py) */
#elif DEPTH_FORMAT == DEPTH_FLOAT32
#  if !RASTER_DEPTH /* orthographic tiles rasterise this depth already (frame/programs.py) */
  gl_FragDepth = clamp((v_distance - tile.near) / (tile.far - tile.near), 0.0, 1.0);
#  endif
#else
  float d = clamp((v_distance - tile.near) / (tile.far - tile.near), 0.0, 1.0);
  out_depth = encode_depth(d);
#endif
}
