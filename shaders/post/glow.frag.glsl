/* GLOW, one of two passes (see glow.py; the bright-pass reference is glow.bright_pass).
 * GLOW_COMPOSITE 0: horizontal blur of the bright-passed source -> rgb, alpha 0.
 * GLOW_COMPOSITE 1: vertical blur of that, added to the source's rgb times intensity.
 * Samples outside the image are clamped to the edge, as in blur.frag.glsl. */

/* Standard soft-knee bright-pass on the largest component; negative components are cut. */
vec3 bright_pass(vec3 c)
{
  c = max(c, vec3(0.0));
  float b = max(c.r, max(c.g, c.b));
  float soft = clamp(b - threshold + knee, 0.0, 2.0 * knee);
  soft = soft * soft / (4.0 * knee + 1e-5);
  float contribution = max(soft, b - threshold) / max(b, 1e-5);
  return c * contribution;
}

void main()
{
  ivec2 size = textureSize(input_tex, 0);
  ivec2 p = ivec2(gl_FragCoord.xy);
#if GLOW_COMPOSITE
  ivec2 step = ivec2(0, 1);
#else
  ivec2 step = ivec2(1, 0);
#endif
  vec3 acc = vec3(0.0);
  for (int i = -radius; i <= radius; i++) {
    int k = i + radius;
    float w = weights[k / 4].w[k % 4];
    ivec2 q = clamp(p + step * i, ivec2(0), size - 1);
    vec3 s = sanitize(texelFetch(input_tex, q, 0)).rgb;
#if !GLOW_COMPOSITE
    s = bright_pass(s);
    if (square_samples != 0) {
      s *= s;
    }
#endif
    acc += w * s;
  }
#if GLOW_COMPOSITE
  vec4 c = post_source();
  out_color = post_mix(vec4(c.rgb + intensity * acc, c.a));
#else
  out_color = vec4(acc, 0.0);
#endif
}
