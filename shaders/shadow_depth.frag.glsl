/* Linear depth along the light's view axis, normalised to the tile's [near, far], in the
 * selected encoding (float, or the seeds' RGBA8 packing). */
void main()
{
  float d = (v_distance - tile.near) / (tile.far - tile.near);
  out_depth = encode_depth(clamp(d, 0.0, 1.0));
}
