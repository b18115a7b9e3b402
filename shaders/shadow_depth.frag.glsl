/* Linear depth along the light's view axis, normalised to the tile's [near, far]: written as
 * the fragment's depth for FLOAT32 maps (the depth buffer is the map), else as colour in the
 * selected encoding (half float, or the seeds' RGBA8 packing). */
void main()
{
  float d = clamp((v_distance - tile.near) / (tile.far - tile.near), 0.0, 1.0);
#if DEPTH_FORMAT == DEPTH_FLOAT32
  gl_FragDepth = d;
#else
  out_depth = encode_depth(d);
#endif
}
