/* Linear depth along the light's view axis, normalised to the tile's [near, far]: written as
 * the fragment's depth for FLOAT32 maps (the depth buffer is the map), else as colour in the
 * selected encoding (half float, or the seeds' RGBA8 packing). A caster with alpha
 * (ALPHA_CUTOUT) covers a texel in a fraction alpha of the samples, with the lit pass's
 * stratified hash: over a frame its shadow lets 1 - alpha of the light through, as Cycles'
 * transparent shadows; an alpha texture of 0 and 1 casts its exact cut-out in every sample. */
void main()
{
#if ALPHA_CUTOUT
  float coverage = material.alpha;
#  if TEX_ALPHA
  coverage *= SAMPLE_VALUE(alpha, v_uv);
#  endif
  if (coverage <= fract(pixel_hash(gl_FragCoord.xy) + alpha_offset)) {
    discard;
  }
#endif
#if DEPTH_FORMAT == DEPTH_FLOAT32
#  if !RASTER_DEPTH /* orthographic tiles rasterise this depth already (frame/programs.py) */
  gl_FragDepth = clamp((v_distance - tile.near) / (tile.far - tile.near), 0.0, 1.0);
#  endif
#else
  float d = clamp((v_distance - tile.near) / (tile.far - tile.near), 0.0, 1.0);
  out_depth = encode_depth(d);
#endif
}
