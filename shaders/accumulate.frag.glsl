/* One sample's contribution to a multi-sample frame: weight * sample, added to the float32
 * accumulation by the blend state (one + one). */
void main()
{
  ivec2 p = ivec2(gl_FragCoord.xy);
  out_color = weight * texelFetch(sample_color, p, 0);
#if WITH_SHADOW
  out_shadow = vec4(weight * texelFetch(sample_shadow, p, 0).r);
#endif
}
