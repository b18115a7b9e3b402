/* One 1-D pass of the separable Gaussian. Weights come normalised from Python (kernels.py);
 * samples outside the image are clamped to the edge. */
void main()
{
  ivec2 size = textureSize(input_tex, 0);
  ivec2 p = ivec2(gl_FragCoord.xy);
  ivec2 step = ivec2(direction);
  vec4 acc = vec4(0.0);
  for (int i = -radius; i <= radius; i++) {
    int k = i + radius;
    float w = weights[k / 4].w[k % 4];
    ivec2 q = clamp(p + step * i, ivec2(0), size - 1);
    acc += w * sanitize(texelFetch(input_tex, q, 0));
  }
  out_color = post_mix(acc);
}
