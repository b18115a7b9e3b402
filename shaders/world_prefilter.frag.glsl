/* One level of the world's prefiltered environment (engine/frame/world/prefilter.py,
 * lib/world_env.glsl): for the direction of each texel of the level, the source image's
 * radiance over ``sample_count`` GGX directions of alpha ``level_alpha`` about it, with
 * N = V = R, weighted by their cosine (Karis 2013). The source is the Environment Texture
 * box-filtered to a size that holds what the lobe shows (``source_level``: the whole source
 * texture), its texels clamped to ``source_clamp`` where the world's sun took the light above it
 * (0: none). A level of alpha 0 is the source itself. */
void main()
{
  vec2 px = gl_FragCoord.xy - vec2(0.0, float(target_level.x));
  vec2 uv = px / vec2(target_level.yz);
  vec3 N = equirect_direction(uv);
  vec3 sum = vec3(0.0);
  float weight = 0.0;
  for (int i = 0; i < sample_count; i++) {
    vec3 H = ggx_half_vector(hammersley(i, sample_count), level_alpha, N);
    vec3 L = 2.0 * dot(N, H) * H - N;
    float NdotL = dot(N, L);
    if (NdotL > 0.0) {
      vec3 c = max(equirect_bilinear(source, source_level, equirect_uv(L)).rgb, vec3(0.0));
      if (source_clamp > 0.0) {
        c = min(c, vec3(source_clamp));
      }
      sum += c * NdotL;
      weight += NdotL;
    }
  }
  out_color = vec4(sum / max(weight, 1e-6), 1.0);
}
