// requires: lib/common.glsl
#ifndef PENUMBRA_LIB_LIGHTS
#define PENUMBRA_LIB_LIGHTS

/* Blender's light conventions, measured against Cycles:
 *   sun   irradiance  E = strength * cos
 *   point/spot        E = P / (4 pi) * cos / (d^2 + r^2)   (soft falloff)
 *   spot  mask        smoothstep((cos a - cos(size/2)) / ((1 - cos(size/2)) * blend)), a measured
 *                     with the light's X/Y scale (over Z) undone: a scaled spot lights an ellipse
 *   area  (far field) E = P / pi * cos * cos_emitter / d^2
 * Outgoing diffuse radiance is albedo / pi * E; LightData.color already holds
 * colour * energy * 2^exposure. */

/* Direction towards the light and the irradiance it delivers on a surface facing it. */
void light_incident(LightData L, vec3 P, out vec3 to_light, out float irradiance)
{
  if (L.type == LIGHT_SUN) {
    to_light = -L.direction;
    irradiance = 1.0;
    return;
  }
  vec3 d = L.position - P;
  float dist2 = dot(d, d);
  to_light = d * inversesqrt(max(dist2, 1e-30));
  float r = L.radius;
  if (L.type == LIGHT_AREA) {
    float cos_emit = max(dot(-to_light, L.direction), 0.0);
    irradiance = cos_emit / (M_PI * max(dist2, 1e-30));
    return;
  }
  irradiance = 1.0 / (4.0 * M_PI * max(dist2 + r * r, 1e-30));
  if (L.type == LIGHT_SPOT) {
    /* The angle from the axis after undoing the object's X/Y scale (an elliptical cone, as in
     * Blender's engines); with uniform scale it is the plain angle. */
    vec3 l = -to_light;
    float z = dot(l, L.direction);
    vec2 xy = vec2(dot(l, L.spot_right) / L.spot_scale_x, dot(l, L.spot_up) / L.spot_scale_y);
    float cos_a = (z > 0.0) ? z * inversesqrt(z * z + dot(xy, xy)) : -1.0;
    float t = cos_a - L.spot_cos_half;
    if (t <= 0.0) {
      irradiance = 0.0;
    }
    else if (L.spot_blend_width > 0.0) {
      float s = saturate(t / L.spot_blend_width);
      irradiance *= s * s * (3.0 - 2.0 * s);
    }
  }
}

#endif /* PENUMBRA_LIB_LIGHTS */
