/* Colour lookup indexed by (blurred luminance, distance to the centre); see colorizer.py for the
 * exact coordinates. luma_tex is the (possibly blurred) layer input; lut_tex row 0 = centre. */

/* Bilinear read of lut_tex at texel coordinate t (0 = centre of the first texel), clamped to the
 * edge texels; NaN/Inf texels read as 0. Done by hand so the weights are exact floats,
 * independent of the texture's sampler state. */
vec3 lut_bilinear(vec2 t)
{
  ivec2 size = textureSize(lut_tex, 0);
  t = clamp(t, vec2(0.0), vec2(size - 1));
  ivec2 i0 = ivec2(floor(t));
  ivec2 i1 = min(i0 + 1, size - 1);
  vec2 f = t - vec2(i0);
  vec3 c00 = sanitize(texelFetch(lut_tex, i0, 0)).rgb;
  vec3 c10 = sanitize(texelFetch(lut_tex, ivec2(i1.x, i0.y), 0)).rgb;
  vec3 c01 = sanitize(texelFetch(lut_tex, ivec2(i0.x, i1.y), 0)).rgb;
  vec3 c11 = sanitize(texelFetch(lut_tex, i1, 0)).rgb;
  return mix(mix(c00, c10, f.x), mix(c01, c11, f.x), f.y);
}

void main()
{
  vec4 c = post_source();
  vec3 blurred = sanitize(texelFetch(luma_tex, ivec2(gl_FragCoord.xy), 0)).rgb;
  float x = saturate(dot(blurred, vec3(0.2126, 0.7152, 0.0722)));
  vec2 half_size = 0.5 * target_size;
  float y = saturate(length(gl_FragCoord.xy - half_size) / length(half_size));
  vec2 lut_size = vec2(textureSize(lut_tex, 0));
  vec3 graded = lut_bilinear(vec2(x, y) * (lut_size - 1.0));
  out_color = post_mix(vec4(mix(c.rgb, graded, strength), c.a));
}
