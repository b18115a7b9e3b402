// requires: lib/common.glsl lib/lights.glsl lib/material.glsl
#ifndef PENUMBRA_LIB_VOLUMES
#define PENUMBRA_LIB_VOLUMES

/* Homogeneous participating media (engine/frame/features/volumes.py): the block ``media``
 * holds frame.volume_params.x of them (MediumData: the map of world positions, relative to the
 * frame origin, into a box's [-1, 1]^3; extinction, scattering and emission per unit of
 * length, RGB; the Henyey-Greenstein g). A WORLD medium fills the sphere of the camera's clip
 * end (frame.volume_params.y) about the camera. Within a medium every coefficient is constant,
 * so the optical depth along a ray is exact: the sum of each medium's extinction times the
 * length of the ray inside it (Beer-Lambert, no marching). Compiled only with VOLUMES (the
 * technique's part of the lit program, and its march). */

#if VOLUMES

#define MEDIUM_WORLD 0
#define MEDIUM_BOX 1
#define FAR_AWAY 3.0e38

/* The part [x, y] of the ray o + t d (unit d) with 0 <= t <= tmax inside medium m; empty
 * when x >= y. Axis-parallel rays take no division by zero: a slab the ray runs along either
 * holds all of it or none. */
vec2 medium_span(MediumData m, vec3 o, vec3 d, float tmax)
{
  if (m.kind == MEDIUM_WORLD) {
    vec3 oc = o - frame.camera_position;
    float r = frame.volume_params.y;
    float b = dot(oc, d);
    float c = dot(oc, oc) - r * r;
    float disc = b * b - c;
    if (disc <= 0.0) {
      return vec2(0.0);
    }
    float h = sqrt(disc);
    return vec2(max(-b - h, 0.0), min(-b + h, tmax));
  }
  vec3 lo = (m.to_unit * vec4(o, 1.0)).xyz;
  vec3 ld = mat3(m.to_unit) * d;
  float t0 = 0.0, t1 = tmax;
  for (int k = 0; k < 3; k++) {
    if (abs(ld[k]) < 1e-20) {
      if (abs(lo[k]) > 1.0) {
        return vec2(0.0);
      }
      continue;
    }
    float inv = 1.0 / ld[k];
    float a = (-1.0 - lo[k]) * inv, b = (1.0 - lo[k]) * inv;
    t0 = max(t0, min(a, b));
    t1 = min(t1, max(a, b));
  }
  return vec2(t0, t1);
}

/* The optical depth (RGB) of every medium along o + t d, 0 <= t <= tmax. */
vec3 optical_depth(vec3 o, vec3 d, float tmax)
{
  vec3 tau = vec3(0.0);
  for (int i = 0; i < int(frame.volume_params.x); i++) {
    vec2 s = medium_span(media[i], o, d, tmax);
    tau += media[i].extinction * max(s.y - s.x, 0.0);
  }
  return tau;
}

/* exp(-tau), 0 past any float's reach (never NaN). */
vec3 transmittance(vec3 tau)
{
  return exp(-min(tau, vec3(80.0)));
}

/* What the media let through of light i's light from the light to P (``to_light`` unit): a
 * sun's from as far as the media reach, a local light's from its centre. */
vec3 light_transmittance(vec3 P, LightData L, vec3 to_light)
{
  float dist = (L.type == LIGHT_SUN) ? FAR_AWAY : length(L.position - P);
  return transmittance(optical_depth(P, to_light, dist));
}

/* What the media let through of the world's light reaching P around normal N: along one
 * direction of the cosine lobe about N, drawn anew each pixel and sample (pixel_r2: the R2
 * sequence over the samples), so a frame's samples average the lobe's transmittance. */
vec3 world_transmittance(vec3 P, vec3 N)
{
  vec2 uv = pixel_r2(29.0, frame.sample_index);
  float u = uv.x, v = uv.y;
  vec3 t = normalize(abs(N.z) < 0.9 ? cross(N, vec3(0.0, 0.0, 1.0)) : cross(N, vec3(1.0, 0.0, 0.0)));
  vec3 b = cross(N, t);
  float r = sqrt(u), phi = 2.0 * M_PI * v;
  vec3 dir = normalize(r * cos(phi) * t + r * sin(phi) * b + sqrt(max(1.0 - u, 0.0)) * N);
  return transmittance(optical_depth(P, dir, FAR_AWAY));
}

/* Whether P is inside medium m. */
bool medium_holds(MediumData m, vec3 P)
{
  if (m.kind == MEDIUM_WORLD) {
    vec3 d = P - frame.camera_position;
    return dot(d, d) <= frame.volume_params.y * frame.volume_params.y;
  }
  vec3 u = (m.to_unit * vec4(P, 1.0)).xyz;
  return all(lessThanEqual(abs(u), vec3(1.0)));
}

/* Henyey-Greenstein: the probability density (per steradian) of scattering by angle theta
 * from the direction of travel, cos_theta its cosine. */
float phase_hg(float g, float cos_theta)
{
  float d = 1.0 + g * g - 2.0 * g * cos_theta;
  return (1.0 - g * g) / (4.0 * M_PI * d * sqrt(max(d, 1e-12)));
}

#endif /* VOLUMES */

#endif /* PENUMBRA_LIB_VOLUMES */
