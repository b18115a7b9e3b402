/* Adaptive sampling's convergence check (film_programs.CONVERGENCE), Cycles' estimate: the mean of
 * all samples I against the mean A of every other sample (times half_scale: the whole weight
 * over the odd samples'), per pixel
 *   error = (|I.r - A.r| + |I.g - A.g| + |I.b - A.b| + |I.a - A.a|) / (0.0001 + sqrt(I.r + I.g + I.b))
 * (Cycles leaves alpha out; here a transparent film's edges count too). A pixel converges when
 * the error of every pixel of its 3x3 neighbourhood is below the threshold (Cycles dilates
 * the unconverged pixels likewise), and once converged it stays so. With ERROR_OUTPUT it writes
 * the estimate instead (the NOISE debug view). With WORLD_RATIO both means take the world's
 * light through its ratio, so the noise of its directions counts. */

#ifndef WORLD_RATIO /* on with the world ratio's part of the check (engine/frame/features/world_ratio.py) */
#  define WORLD_RATIO 0
#endif

/* The error estimate of pixel q (0 for a pixel with no samples yet). */
float pixel_error(ivec2 q)
{
  float n = (per_pixel > 0.5) ? texelFetch(weight, q, 0).r : weight_sum;
  if (n <= 0.0) {
    return 0.0;
  }
  vec4 I = texelFetch(accum, q, 0) / n;
  vec4 A = half_scale * texelFetch(half_accum, q, 0) / n;
#if WORLD_RATIO
  /* The world's light through its ratio in both means (lib/world_ratio.glsl): the SH light
   * by lobe of all samples, the sums of all samples and of every other one. */
  vec3 u_d = texelFetch(world_diffuse, q, 0).rgb / n, u_s = texelFetch(world_specular, q, 0).rgb / n;
  I = world_ratio_apply(I, u_d, u_s, texelFetch(world_sums, q, 0));
  A = world_ratio_apply(A, u_d, u_s, half_scale * texelFetch(half_world_sums, q, 0));
#endif
  vec4 d = abs(I - A);
  return (d.r + d.g + d.b + d.a) / (0.0001 + sqrt(max(I.r + I.g + I.b, 0.0)));
}

bool below(ivec2 q)
{
  if (texelFetch(converged, q, 0).r > 0.5) {
    return true;
  }
  float n = (per_pixel > 0.5) ? texelFetch(weight, q, 0).r : weight_sum;
  return n > 0.0 && pixel_error(q) < threshold;
}

void main()
{
  ivec2 p = ivec2(gl_FragCoord.xy);
  ivec2 size = textureSize(accum, 0);
#if ERROR_OUTPUT
  /* The NOISE debug view: what the check compares with the threshold, the largest error of
   * the 3x3 neighbourhood, in units of the Noise Threshold (threshold = its scale). */
  float worst = 0.0;
  for (int y = -1; y <= 1; y++) {
    for (int x = -1; x <= 1; x++) {
      worst = max(worst, pixel_error(clamp(p + ivec2(x, y), ivec2(0), size - 1)));
    }
  }
  out_color = vec4(worst / threshold);
  return;
#endif
  bool done = texelFetch(converged, p, 0).r > 0.5;
  if (!done) {
    done = true;
    for (int y = -1; y <= 1; y++) {
      for (int x = -1; x <= 1; x++) {
        ivec2 q = clamp(p + ivec2(x, y), ivec2(0), size - 1);
        done = done && below(q);
      }
    }
  }
  out_color = vec4(done ? 1.0 : 0.0);
}
