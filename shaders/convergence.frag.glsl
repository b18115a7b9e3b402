/* Adaptive sampling's convergence check (programs.CONVERGENCE), Cycles' estimate: the mean of
 * all samples I against the mean A of every other sample (accumulated twice over), per pixel
 *   error = (|I.r - A.r| + |I.g - A.g| + |I.b - A.b| + |I.a - A.a|) / (0.0001 + sqrt(I.r + I.g + I.b))
 * (Cycles leaves alpha out; here a transparent film's edges count too). A pixel converges when
 * the error of every pixel of its 3x3 neighbourhood is below the threshold (Cycles dilates
 * the unconverged pixels likewise), and once converged it stays so. */

bool below(ivec2 q)
{
  if (texelFetch(converged, q, 0).r > 0.5) {
    return true;
  }
  float n = (per_pixel > 0.5) ? texelFetch(weight, q, 0).r : weight_sum;
  if (n <= 0.0) {
    return false;
  }
  vec4 I = texelFetch(accum, q, 0) / n;
  vec4 A = texelFetch(half_accum, q, 0) / n;
  vec4 d = abs(I - A);
  float error = (d.r + d.g + d.b + d.a) / (0.0001 + sqrt(max(I.r + I.g + I.b, 0.0)));
  return error < threshold;
}

void main()
{
  ivec2 p = ivec2(gl_FragCoord.xy);
  ivec2 size = textureSize(accum, 0);
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
