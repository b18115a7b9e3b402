/* Colour lookup indexed by (blurred luminance, distance to the centre); see colorizer.py for the
 * exact coordinates. luma_tex is the (possibly blurred) layer input; lut_tex row 0 = centre. */

void main()
{
  vec4 c = post_source();
  vec3 blurred = sanitize(texelFetch(luma_tex, ivec2(gl_FragCoord.xy), 0)).rgb;
  float x = saturate(dot(blurred, vec3(0.2126, 0.7152, 0.0722)));
  vec2 half_size = 0.5 * target_size;
  float y = saturate(length(gl_FragCoord.xy - half_size) / length(half_size));
  vec2 lut_size = vec2(textureSize(lut_tex, 0));
  vec3 graded = texel_bilinear(lut_tex, vec2(x, y) * (lut_size - 1.0));
  out_color = post_mix(vec4(mix(c.rgb, graded, strength), c.a));
}
