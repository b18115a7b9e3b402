/* Input nodes that compute something (Blender manual: Fresnel, Layer Weight). ``V`` points
 * from the surface towards the viewer, ``front``: the side of the surface the mesh's normal
 * points to is seen. */

#ifndef NODE_INPUT_GLSL
#define NODE_INPUT_GLSL

float node_fresnel_dielectric(float cosi, float eta)
{
  float c = abs(cosi);
  float g = eta * eta - 1.0 + c * c;
  if (g > 0.0) {
    g = sqrt(g);
    float A = (g - c) / (g + c);
    float B = (c * (g + c) - 1.0) / (c * (g - c) + 1.0);
    return 0.5 * A * A * (1.0 + B * B);
  }
  return 1.0; /* total internal reflection */
}

float node_fresnel(float ior, vec3 N, vec3 V, bool front)
{
  float eta = max(ior, 1e-5);
  return node_fresnel_dielectric(dot(V, node_safe_normalize(N)), front ? eta : 1.0 / eta);
}

/* Layer Weight: x Fresnel, y Facing. */
vec2 node_layer_weight(float blend, vec3 N, vec3 V, bool front)
{
  N = node_safe_normalize(N);
  float eta = max(1.0 - blend, 1e-5);
  float fresnel = node_fresnel_dielectric(dot(V, N), front ? 1.0 / eta : eta);
  float facing = abs(dot(V, N));
  if (blend != 0.5) {
    blend = clamp(blend, 0.0, 0.99999);
    blend = (blend < 0.5) ? 2.0 * blend : 0.5 / (1.0 - blend);
    facing = pow(facing, blend);
  }
  return vec2(fresnel, 1.0 - facing);
}

#endif
