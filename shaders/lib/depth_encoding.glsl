// requires:
#ifndef PENUMBRA_LIB_DEPTH_ENCODING
#define PENUMBRA_LIB_DEPTH_ENCODING

/* Shadow depth in [0, 1] as stored in the atlas. FLOAT32/FLOAT16 use the red channel of a
 * float texture; RGBA8 packs it into four 8-bit channels (the fixed-point split used where
 * float targets are unavailable, as in WebGL 1), giving about 32 bits of fixed-point
 * precision from a plain RGBA8 target. */
vec4 encode_depth(float d)
{
#if DEPTH_FORMAT == DEPTH_RGBA8
  vec4 enc = fract(d * vec4(1.0, 255.0, 65025.0, 16581375.0));
  enc -= enc.yzww * vec4(1.0 / 255.0, 1.0 / 255.0, 1.0 / 255.0, 0.0);
  return (d >= 1.0) ? vec4(1.0) : enc;
#else
  return vec4(d, 0.0, 0.0, 1.0);
#endif
}

float decode_depth(vec4 texel)
{
#if DEPTH_FORMAT == DEPTH_RGBA8
  return dot(texel, vec4(1.0, 1.0 / 255.0, 1.0 / 65025.0, 1.0 / 16581375.0));
#else
  return texel.r;
#endif
}

#endif /* PENUMBRA_LIB_DEPTH_ENCODING */
