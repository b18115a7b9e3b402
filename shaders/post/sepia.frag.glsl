/* sepia_r/g/b = rows of sepia.py's SEPIA_MATRIX (w unused); amount blends it in. */
void main()
{
  vec4 c = post_source();
  vec3 s = vec3(dot(sepia_r.rgb, c.rgb), dot(sepia_g.rgb, c.rgb), dot(sepia_b.rgb, c.rgb));
  out_color = post_mix(vec4(mix(c.rgb, s, amount), c.a));
}
