/* GLOW, one pass of it (see glow.py; the references are glow.bright_pass, glow_reference).
 * Full resolution, two passes:
 *   GLOW_BRIGHT_H     horizontal blur of the bright-passed source -> rgb, alpha 0
 *   GLOW_COMPOSITE_V  vertical blur of that, added to the source's rgb times intensity
 * Half resolution, four passes (a quarter of the pixels, half the taps):
 *   GLOW_DOWN         each half-size pixel: the mean bright-pass of the 2x2 source pixels it
 *                     covers (those inside the image)
 *   GLOW_BLUR_H       horizontal blur, GLOW_BLUR_V vertical blur (half-size images)
 *   GLOW_UP           the half-size glow read bilinearly at this pixel's centre, added to the
 *                     source's rgb times intensity
 * Samples outside the image are clamped to the edge, as in blur.frag.glsl. */

/* Standard soft-knee bright-pass on the largest component; negative components are cut. */
vec3 bright_pass(vec3 c)
{
  c = max(c, vec3(0.0));
  float b = max(c.r, max(c.g, c.b));
  float soft = clamp(b - threshold + knee, 0.0, 2.0 * knee);
  soft = soft * soft / (4.0 * knee + 1e-5);
  float contribution = max(soft, b - threshold) / max(b, 1e-5);
  vec3 s = c * contribution;
  return (square_samples != 0) ? s * s : s;
}

void main()
{
  ivec2 size = textureSize(input_tex, 0);
  ivec2 p = ivec2(gl_FragCoord.xy);
#if GLOW_PASS == GLOW_DOWN
  vec3 sum = vec3(0.0);
  float count = 0.0;
  for (int dy = 0; dy < 2; dy++) {
    for (int dx = 0; dx < 2; dx++) {
      ivec2 q = 2 * p + ivec2(dx, dy);
      if (q.x < size.x && q.y < size.y) {
        sum += bright_pass(sanitize(texelFetch(input_tex, q, 0)).rgb);
        count += 1.0;
      }
    }
  }
  out_color = vec4(sum / max(count, 1.0), 0.0);
#elif GLOW_PASS == GLOW_UP
  vec4 c = post_source();
  vec3 glow = texel_bilinear(input_tex, (vec2(p) + 0.5) * 0.5 - 0.5);
  out_color = post_mix(vec4(c.rgb + intensity * glow, c.a));
#else
#  if GLOW_PASS == GLOW_COMPOSITE_V || GLOW_PASS == GLOW_BLUR_V
  ivec2 step = ivec2(0, 1);
#  else
  ivec2 step = ivec2(1, 0);
#  endif
  vec3 acc = vec3(0.0);
  for (int i = -radius; i <= radius; i++) {
    int k = i + radius;
    float w = weights[k / 4].w[k % 4];
    ivec2 q = clamp(p + step * i, ivec2(0), size - 1);
    vec3 s = sanitize(texelFetch(input_tex, q, 0)).rgb;
#  if GLOW_PASS == GLOW_BRIGHT_H
    s = bright_pass(s);
#  endif
    acc += w * s;
  }
#  if GLOW_PASS == GLOW_COMPOSITE_V
  vec4 c = post_source();
  out_color = post_mix(vec4(c.rgb + intensity * acc, c.a));
#  else
  out_color = vec4(acc, 0.0);
#  endif
#endif
}
