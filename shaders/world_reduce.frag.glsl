/* The world's Environment Texture reduced to the target's size, each target texel the box
 * average of the texels of the image it covers (engine/frame/world/sh_light.py): read from the
 * coarsest mip level still at least the target's size, up to 16 x 16 texels a target texel.
 * NaN reads as 0 and infinities as the half-float limit, so one bad texel cannot make the
 * world's light infinite. A premultiplied texture (env_premultiplied) is made straight per
 * texel, as the Background shader outputs it. */
void main()
{
  ivec2 target = ivec2(target_size);
  ivec2 out_px = ivec2(gl_FragCoord.xy);
  int levels = textureQueryLevels(env);
  int level = 0;
  while (level + 1 < levels && all(greaterThanEqual(textureSize(env, level + 1), target))) {
    level++;
  }
  ivec2 size = textureSize(env, level);
  ivec2 lo = out_px * size / target;
  ivec2 hi = max((out_px + 1) * size / target, lo + 1);
  ivec2 stride = max((hi - lo + 15) / 16, ivec2(1));
  vec4 sum = vec4(0.0);
  float n = 0.0;
  for (int y = lo.y; y < hi.y; y += stride.y) {
    for (int x = lo.x; x < hi.x; x += stride.x) {
      vec4 t = texelFetch(env, clamp(ivec2(x, y), ivec2(0), size - 1), level);
      t = mix(t, vec4(0.0), isnan(t));
      t = clamp(t, vec4(-65504.0), vec4(65504.0));
      if (env_premultiplied > 0.5 && t.a > 0.0) {
        t.rgb /= t.a;
      }
      sum += t;
      n += 1.0;
    }
  }
  out_color = sum / max(n, 1.0);
}
