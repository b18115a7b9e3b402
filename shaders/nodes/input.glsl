// requires: nodes/common.glsl
#ifndef PENUMBRA_LIB_NODES_INPUT
#define PENUMBRA_LIB_NODES_INPUT

/* Input nodes that compute something (Blender manual: Fresnel, Layer Weight). ``V`` points
 * from the surface towards the viewer, ``front``: the side of the surface the mesh's normal
 * points to is seen. */

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

/* Bump: the shading normal tilted by the screen-space gradient of ``height`` over the surface
 * (the surface-gradient form of bump mapping on unparametrised surfaces), Distance scaling the
 * height, Invert and the side seen flipping it, Strength mixing from N. */
vec3 node_bump(float strength, float dist, float height, vec3 N, bool front, bool invert)
{
  N = node_safe_normalize(N);
  float d = dist * (invert ? -1.0 : 1.0) * (front ? 1.0 : -1.0);
  vec3 dpx = dFdx(v_world), dpy = dFdy(v_world);
  vec3 rx = cross(dpy, N), ry = cross(N, dpx);
  float det = dot(dpx, rx);
  vec3 grad = dFdx(height) * rx + dFdy(height) * ry;
  vec3 bumped = node_safe_normalize(abs(det) * N - d * sign(det) * grad);
  if (dot(bumped, bumped) == 0.0) {
    return N;
  }
  return node_safe_normalize(mix(N, bumped, max(strength, 0.0)));
}

#endif /* PENUMBRA_LIB_NODES_INPUT */
