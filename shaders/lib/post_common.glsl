// requires: lib/common.glsl
#ifndef PENUMBRA_LIB_POST_COMMON
#define PENUMBRA_LIB_POST_COMMON

/* The layer's input at this pixel, NaN/Inf removed. */
vec4 post_source()
{
  return sanitize(texelFetch(source_tex, ivec2(gl_FragCoord.xy), 0));
}

/* Blend an effect's result with the layer input; mix_factor 0 returns the input exactly. */
vec4 post_mix(vec4 effected)
{
  vec4 src = post_source();
  return (mix_factor >= 1.0) ? effected : mix(src, effected, mix_factor);
}

/* Bilinear read of tex at texel coordinate t (0 = centre of the first texel), clamped to the
 * edge texels; NaN/Inf texels read as 0. Done by hand so the weights are exact floats,
 * independent of the texture's sampler state. */
vec4 texel_bilinear_rgba(sampler2D tex, vec2 t)
{
  ivec2 size = textureSize(tex, 0);
  t = clamp(t, vec2(0.0), vec2(size - 1));
  ivec2 i0 = ivec2(floor(t));
  ivec2 i1 = min(i0 + 1, size - 1);
  vec2 f = t - vec2(i0);
  vec4 c00 = sanitize(texelFetch(tex, i0, 0));
  vec4 c10 = sanitize(texelFetch(tex, ivec2(i1.x, i0.y), 0));
  vec4 c01 = sanitize(texelFetch(tex, ivec2(i0.x, i1.y), 0));
  vec4 c11 = sanitize(texelFetch(tex, i1, 0));
  return mix(mix(c00, c10, f.x), mix(c01, c11, f.x), f.y);
}

vec3 texel_bilinear(sampler2D tex, vec2 t)
{
  return texel_bilinear_rgba(tex, t).rgb;
}

#endif /* PENUMBRA_LIB_POST_COMMON */
