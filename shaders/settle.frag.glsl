/* The settle mask (features.settling.SETTLE), once after a frame's first
 * sample(s): a pixel settles, taking no further samples, when no later sample can move it
 * by the Noise Threshold. Two causes could:
 *   - a light: the settle test's flags (``flags``: red 1 where no moving light's visibility
 *     or facet can change, green the change of reflected light over the lights' extents),
 *     needed settled ``flag_reach`` pixels each way (as far as the pixel filter reaches);
 *   - the pixel filter: later samples look elsewhere in the pixel. For an image f smooth
 *     over the filter, the samples kept (their offsets' mean m_k and second moments S_k)
 *     differ from the whole frame's (m, S) by
 *       grad f . (m_k - m) + 1/2 tr(H (S_k - S)),
 *     with central differences of the image so far (``accum`` / ``weight_sum``) and K the
 *     largest second difference along the four lines through the pixel (rows, columns,
 *     diagonals). That holds where f is smooth; an edge within a pixel moves the filtered
 *     value by up to half its step, and has a neighbour on its other side (the filter reaches
 *     Filter Size pixels, 1.5 by default, but beyond 1 px it weighs 0.6 % each way):
 *     so the change is bounded by the larger of the smooth estimate and half of R, the
 *     largest departure of a neighbour from the plane through the pixel (its gradient), which
 *     is a step's size at an edge, a thin line or a texture's detail, and small where the
 *     image is smooth.
 * Both in Cycles' error units (sum over RGBA of |change| over sqrt of the pixel's RGB),
 * against ``threshold``; WITH_SHADOW, the Shadow pass's change too (in visibility), so a
 * silhouette between two surfaces of the same colour, one lit and one in shadow, samples on.
 * A pixel already converged stays so. */
void main()
{
  ivec2 p = ivec2(gl_FragCoord.xy);
  if (texelFetch(converged, p, 0).r > 0.5) {
    out_color = vec4(1.0);
    return;
  }
  ivec2 size = textureSize(accum, 0);
  float inv = (weight_sum > 0.0) ? 1.0 / weight_sum : 0.0;
  bool settled = true;
  vec4 c[9];
  for (int y = -1; y <= 1; y++) {
    for (int x = -1; x <= 1; x++) {
      c[(y + 1) * 3 + (x + 1)] = texelFetch(accum, clamp(p + ivec2(x, y), ivec2(0), size - 1), 0) * inv;
    }
  }
  int reach = int(flag_reach + 0.5);
  for (int y = -reach; y <= reach; y++) {
    for (int x = -reach; x <= reach; x++) {
      settled = settled && texelFetch(flags, clamp(p + ivec2(x, y), ivec2(0), size - 1), 0).r > 0.5;
    }
  }
  vec4 fx = 0.5 * (c[5] - c[3]), fy = 0.5 * (c[7] - c[1]);
  vec4 k = max(max(abs(c[5] - 2.0 * c[4] + c[3]), abs(c[7] - 2.0 * c[4] + c[1])),
               max(abs(c[8] - 2.0 * c[4] + c[0]), abs(c[6] - 2.0 * c[4] + c[2])));
  vec3 m2 = abs(moment_shift);
  vec4 change = abs(fx * mean_shift.x) + abs(fy * mean_shift.y) + 0.5 * k * (m2.x + m2.y + 2.0 * m2.z);
  vec4 r = vec4(0.0);
  for (int y = -1; y <= 1; y++) {
    for (int x = -1; x <= 1; x++) {
      r = max(r, abs(c[(y + 1) * 3 + (x + 1)] - c[4] - fx * float(x) - fy * float(y)));
    }
  }
  change = max(change, 0.5 * r);
#if WITH_SHADOW
  {
    float v[9];
    for (int y = -1; y <= 1; y++) {
      for (int x = -1; x <= 1; x++) {
        v[(y + 1) * 3 + (x + 1)] = texelFetch(accum_shadow, clamp(p + ivec2(x, y), ivec2(0), size - 1), 0).r * inv;
      }
    }
    float ks = max(max(abs(v[5] - 2.0 * v[4] + v[3]), abs(v[7] - 2.0 * v[4] + v[1])),
                   max(abs(v[8] - 2.0 * v[4] + v[0]), abs(v[6] - 2.0 * v[4] + v[2])));
    float sx = 0.5 * (v[5] - v[3]), sy = 0.5 * (v[7] - v[1]);
    float shadow_change = abs(sx * mean_shift.x) + abs(sy * mean_shift.y) + 0.5 * ks * (m2.x + m2.y + 2.0 * m2.z);
    for (int y = -1; y <= 1; y++) {
      for (int x = -1; x <= 1; x++) {
        shadow_change = max(shadow_change, 0.5 * abs(v[(y + 1) * 3 + (x + 1)] - v[4] - sx * float(x) - sy * float(y)));
      }
    }
    settled = settled && shadow_change < threshold;
  }
#endif
  vec4 I = c[4];
  float spread = texelFetch(flags, p, 0).g;
  float error = (dot(change, vec4(1.0)) + spread) / (0.0001 + sqrt(max(I.r + I.g + I.b, 0.0)));
  out_color = vec4((settled && error < threshold) ? 1.0 : 0.0);
}
