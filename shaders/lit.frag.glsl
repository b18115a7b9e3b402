/* Forward lighting: Lambert diffuse + normalised Blinn or Phong specular, world colour as
 * ambient (albedo * world, what Cycles gives an unoccluded surface), each light attenuated
 * by its shadow visibility. Back faces of a light (N.L <= 0) skip the shadow filter.
 *
 * The lit pass pays only for what it uses: lights sampled over their extent come first
 * (frame.sampled_count, PCSS of their per-sample size), then the other lights with a shadow
 * map (up to frame.shadowed_count, the scene's filter), then lights without a map (no filter
 * code); a scene without lights runs no loop. With several
 * local lights, each pixel loops only over the lights its screen bin lists. */

struct Surface {
  vec3 P, N, V;
  vec3 albedo, f0;
  float shininess;
};

#define NO_SHADOW -1

/* Add light i's contribution. ``filter_id`` is a literal at each call (FILTER_* or NO_SHADOW), so
 * the compiler keeps a shadow filter only where a light has a map, and only that one. */
void add_light(int i, const int filter_id, Surface s, inout vec3 color, inout float arriving,
               inout float unshadowed)
{
  LightData L = lights[i];
  vec3 to_light;
  float irradiance;
  light_incident(L, s.P, to_light, irradiance);
  float NdotL = dot(s.N, to_light);
  if (NdotL <= 0.0 || irradiance <= 0.0) {
    return;
  }
  /* Shadow pass: direct light that arrives over direct light that would arrive unshadowed,
   * each light weighted by the luminance of its irradiance here (1 where no light reaches). */
  float weight = dot(L.color, vec3(0.2126, 0.7152, 0.0722)) * irradiance * NdotL;
  float visibility = (filter_id == NO_SHADOW) ? 1.0 : shadow_visibility(L, s.P, s.N, NdotL, filter_id);
  unshadowed += weight;
  arriving += weight * visibility;
#if SPECULAR_MODEL == SPECULAR_BLINN
  vec3 H = normalize(to_light + s.V);
  float spec = (s.shininess + 8.0) / (8.0 * M_PI) * pow(max(dot(s.N, H), 0.0), s.shininess);
#else
  vec3 R = reflect(-to_light, s.N);
  float spec = (s.shininess + 2.0) / (2.0 * M_PI) * pow(max(dot(R, s.V), 0.0), s.shininess);
#endif
  vec3 E = L.color * (irradiance * NdotL * visibility);
  color += E * (s.albedo / M_PI + s.f0 * spec);
}

void main()
{
  Surface s;
  s.P = v_world;
  vec3 N = v_normal;
  float nlen = length(N);
  if (!(nlen > 1e-20)) {
    /* Degenerate normal (zero-scale or broken mesh): fall back to the face normal. */
    N = cross(dFdx(s.P), dFdy(s.P));
    nlen = length(N);
  }
  N = (nlen > 1e-30) ? N / nlen : vec3(0.0, 0.0, 1.0);

  s.V = (frame.is_ortho != 0) ? -frame.camera_forward : normalize(frame.camera_position - s.P);
  if (dot(N, s.V) < 0.0) {
    N = -N; /* two-sided, as Blender draws meshes */
  }
  s.N = N;

  vec3 base = base_color.rgb;
  float rough = clamp(roughness, 0.0, 1.0);
  float spec_level = max(specular, 0.0);
  float metal = clamp(metallic, 0.0, 1.0);
  s.albedo = base * (1.0 - metal);
  s.f0 = mix(vec3(0.08 * spec_level), base, metal);
  float alpha = max(rough * rough, 0.02);
  s.shininess = 2.0 / (alpha * alpha) - 2.0;

  vec3 color = s.albedo * frame.world_color;
  float arriving = 0.0, unshadowed = 0.0;
#if LIGHT_BINS
  /* Only the lights this pixel's screen bin lists (engine/light_bins.py): word w of the bin
   * holds lights w * LIGHT_WORD_BITS + bit, as exact small integers in a float channel. */
  vec4 words = texelFetch(light_bins, ivec2(gl_FragCoord.xy) / LIGHT_BIN_SIZE, 0);
#  if SAMPLED_LIGHTS
  for (int w = 0; w < LIGHT_WORDS; w++) {
    uint bits = uint(words[w]) & uint(frame.sampled_mask[w]);
    while (bits != 0u) {
      int b = findLSB(bits);
      bits &= bits - 1u;
      add_light(w * LIGHT_WORD_BITS + b, FILTER_PCSS, s, color, arriving, unshadowed);
    }
  }
#  endif
  for (int w = 0; w < LIGHT_WORDS; w++) {
    uint bits = uint(words[w]) & uint(frame.shadowed_mask[w]) & ~uint(frame.sampled_mask[w]);
    while (bits != 0u) {
      int b = findLSB(bits);
      bits &= bits - 1u;
      add_light(w * LIGHT_WORD_BITS + b, SHADOW_FILTER, s, color, arriving, unshadowed);
    }
  }
  for (int w = 0; w < LIGHT_WORDS; w++) {
    uint bits = uint(words[w]) & ~uint(frame.shadowed_mask[w]);
    while (bits != 0u) {
      int b = findLSB(bits);
      bits &= bits - 1u;
      add_light(w * LIGHT_WORD_BITS + b, NO_SHADOW, s, color, arriving, unshadowed);
    }
  }
#else
#  if SAMPLED_LIGHTS
  for (int i = 0; i < frame.sampled_count; i++) {
    add_light(i, FILTER_PCSS, s, color, arriving, unshadowed);
  }
#  endif
  for (int i = frame.sampled_count; i < frame.shadowed_count; i++) {
    add_light(i, SHADOW_FILTER, s, color, arriving, unshadowed);
  }
  for (int i = frame.shadowed_count; i < frame.light_count; i++) {
    add_light(i, NO_SHADOW, s, color, arriving, unshadowed);
  }
#endif
  out_color = vec4(color, 1.0);
#if AUX_OUTPUTS
  out_depth = v_view_depth;
  out_shadow = (unshadowed > 0.0) ? arriving / unshadowed : 1.0;
  out_normal = vec4(N, 0.0); /* world-space shading normal, facing the camera (Normal pass) */
#endif
}
