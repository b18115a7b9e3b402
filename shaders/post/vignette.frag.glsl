/* See vignette.py's vignette_factor. */
void main()
{
  vec4 c = post_source();
  float aspect = target_size.x / target_size.y;
  vec2 p = (gl_FragCoord.xy / target_size - 0.5) * 2.0;
  p.x *= 1.0 + (aspect - 1.0) * roundness;
  float d = length(p);
  float f;
  if (softness <= 0.0) {
    f = (d > radius) ? 1.0 : 0.0;
  }
  else {
    float t = saturate((d - radius) / softness);
    f = t * t * (3.0 - 2.0 * t);
  }
  out_color = post_mix(vec4(mix(c.rgb, vignette_color.rgb, f), c.a));
}
