/* BLUR_PASS selects the pass (blur.py's PASS):
 *   BLUR_AXIS   one 1-D pass of the separable Gaussian along ``direction``. Weights come
 *               normalised from Python (engine/shadows/kernels.py); samples outside the image are clamped to
 *               the edge.
 *   BLUR_DOWN   each half-size pixel: the mean of the 2x2 input pixels it covers (those inside
 *               the image)
 *   BLUR_UP     the half-size blur read bilinearly at this pixel's centre */
void main()
{
  ivec2 size = textureSize(input_tex, 0);
  ivec2 p = ivec2(gl_FragCoord.xy);
#if BLUR_PASS == BLUR_DOWN
  vec4 sum = vec4(0.0);
  float count = 0.0;
  for (int dy = 0; dy < 2; dy++) {
    for (int dx = 0; dx < 2; dx++) {
      ivec2 q = 2 * p + ivec2(dx, dy);
      if (q.x < size.x && q.y < size.y) {
        sum += sanitize(texelFetch(input_tex, q, 0));
        count += 1.0;
      }
    }
  }
  out_color = sum / max(count, 1.0);
#elif BLUR_PASS == BLUR_UP
  out_color = post_mix(texel_bilinear_rgba(input_tex, (vec2(p) + 0.5) * 0.5 - 0.5));
#else
  ivec2 step = ivec2(direction);
  vec4 acc = vec4(0.0);
  for (int i = -radius; i <= radius; i++) {
    int k = i + radius;
    float w = weights[k / 4].w[k % 4];
    ivec2 q = clamp(p + step * i, ivec2(0), size - 1);
    acc += w * sanitize(texelFetch(input_tex, q, 0));
  }
  out_color = post_mix(acc);
#endif
}
