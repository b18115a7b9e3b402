/* Forward lighting: Lambert diffuse + normalised Blinn or Phong specular, world colour as
 * ambient (albedo * world, what Cycles gives an unoccluded surface), each light attenuated
 * by its shadow visibility. Back faces of a light (N.L <= 0) skip the shadow filter. */
void main()
{
  vec3 P = v_world;
  vec3 N = v_normal;
  float nlen = length(N);
  if (!(nlen > 1e-20)) {
    /* Degenerate normal (zero-scale or broken mesh): fall back to the face normal. */
    N = cross(dFdx(P), dFdy(P));
    nlen = length(N);
  }
  N = (nlen > 1e-30) ? N / nlen : vec3(0.0, 0.0, 1.0);

  vec3 V = (frame.is_ortho != 0) ? -frame.camera_forward : normalize(frame.camera_position - P);
  if (dot(N, V) < 0.0) {
    N = -N; /* two-sided, as Blender draws meshes */
  }

  vec3 base = base_color.rgb;
  float rough = clamp(roughness, 0.0, 1.0);
  float spec_level = max(specular, 0.0);
  float metal = clamp(metallic, 0.0, 1.0);
  vec3 albedo = base * (1.0 - metal);
  vec3 f0 = mix(vec3(0.08 * spec_level), base, metal);
  float alpha = max(rough * rough, 0.02);
  float shininess = 2.0 / (alpha * alpha) - 2.0;

  vec3 color = albedo * frame.world_color;
  /* Shadow pass: direct light that arrives over direct light that would arrive unshadowed,
   * each light weighted by the luminance of its irradiance here (1 where no light reaches). */
  float arriving = 0.0, unshadowed = 0.0;
  for (int i = 0; i < frame.light_count; i++) {
    LightData L = lights[i];
    vec3 to_light;
    float irradiance;
    light_incident(L, P, to_light, irradiance);
    float NdotL = dot(N, to_light);
    if (NdotL <= 0.0 || irradiance <= 0.0) {
      continue;
    }
    float weight = dot(L.color, vec3(0.2126, 0.7152, 0.0722)) * irradiance * NdotL;
    float visibility = shadow_visibility(L, P, N, NdotL);
    unshadowed += weight;
    arriving += weight * visibility;
    if (visibility <= 0.0) {
      continue;
    }
#if SPECULAR_MODEL == SPECULAR_BLINN
    vec3 H = normalize(to_light + V);
    float spec = (shininess + 8.0) / (8.0 * M_PI) * pow(max(dot(N, H), 0.0), shininess);
#else
    vec3 R = reflect(-to_light, N);
    float spec = (shininess + 2.0) / (2.0 * M_PI) * pow(max(dot(R, V), 0.0), shininess);
#endif
    vec3 E = L.color * (irradiance * NdotL * visibility);
    color += E * (albedo / M_PI + f0 * spec);
  }
  out_color = vec4(color, 1.0);
  out_depth = v_view_depth;
  out_shadow = (unshadowed > 0.0) ? arriving / unshadowed : 1.0;
  out_normal = vec4(N, 0.0); /* world-space shading normal, facing the camera (Normal pass) */
}
