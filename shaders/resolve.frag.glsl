/* The filtered average of a multi-sample frame: accumulation / total weight. */
void main()
{
  ivec2 p = ivec2(gl_FragCoord.xy);
  out_color = inv_weight * texelFetch(accum_color, p, 0);
#if WITH_SHADOW
  out_shadow = vec4(inv_weight * texelFetch(accum_shadow, p, 0).r);
#endif
}
