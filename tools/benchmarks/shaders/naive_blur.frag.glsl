/* Direct 2-D Gaussian: (2r+1)^2 taps per pixel, the cost the separable blur avoids. Uses the
 * same normalised 1-D weights as the separable pass (the 2-D kernel is their outer product). */
void main()
{
  ivec2 size = textureSize(source_tex, 0);
  ivec2 p = ivec2(gl_FragCoord.xy);
  vec4 acc = vec4(0.0);
  for (int j = -radius; j <= radius; j++) {
    int kj = j + radius;
    float wj = weights[kj / 4].w[kj % 4];
    for (int i = -radius; i <= radius; i++) {
      int ki = i + radius;
      float wi = weights[ki / 4].w[ki % 4];
      ivec2 q = clamp(p + ivec2(i, j), ivec2(0), size - 1);
      acc += wi * wj * sanitize(texelFetch(source_tex, q, 0));
    }
  }
  out_color = post_mix(acc);
}
