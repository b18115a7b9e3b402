#ifndef POST_COMMON_GLSL
#define POST_COMMON_GLSL

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

#endif
