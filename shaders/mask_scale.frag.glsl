/* Every channel of the target times the converged mask (drawn with multiplicative blending,
 * programs.MASK_SCALE): after the pilot sample only settled pixels keep what it added
 * (engine/frame/settle.py). */
void main()
{
  out_color = vec4(texelFetch(converged, ivec2(gl_FragCoord.xy), 0).r);
}
