// requires: nodes/texture_hash.glsl nodes/texture_noise.glsl
#ifndef PENUMBRA_LIB_NODES_TEXTURE_WAVE
#define PENUMBRA_LIB_NODES_TEXTURE_WAVE

/* Blender's Wave Texture node: bands or rings of a periodic profile, perturbed by fBM noise.
 *
 * - Bands run along X, Y, Z (the coordinate times 20) or the diagonal (the sum of the three
 *   coordinates times 10); rings are 20 times the distance from an axis (X, Y, Z) or from the
 *   origin (Spherical).
 * - Phase Offset adds to that; Distortion adds Distortion * (2 f - 1), f the normalized fBM of
 *   texture_noise.glsl (lacunarity 2) at the point times Detail Scale, with Detail octaves and
 *   Detail Roughness.
 * - Profiles of the value n: Sine 0.5 + 0.5 sin(n - pi/2), Saw the fractional part of n / 2pi,
 *   Triangle twice the distance of n / 2pi from its nearest integer.
 * - Like Blender, the scaled point is nudged, (p + 1e-6) * 0.999999, so that unit coordinates
 *   do not sit on a band edge.
 *
 * Deviations, on purpose: a non-finite coordinate, or a value that overflows, reads as 0 where
 * Blender would return NaN; Detail is clamped to [0, 15] and Detail Roughness to >= 0 (the
 * sockets' own ranges) so the octave loop stays bounded; the profile is clamped to [0, 1]
 * (Blender's is not: its sin may round past 1). Color is Fac in every channel. */

/* Wave Texture node `wave_type`. */
#define WAVE_BANDS 0
#define WAVE_RINGS 1

/* `bands_direction` (X, Y, Z, DIAGONAL) and `rings_direction` (X, Y, Z, SPHERICAL). */
#define WAVE_X 0
#define WAVE_Y 1
#define WAVE_Z 2
#define WAVE_DIAGONAL 3
#define WAVE_SPHERICAL 3

/* `wave_profile`. */
#define WAVE_SINE 0
#define WAVE_SAW 1
#define WAVE_TRIANGLE 2

/* The wave on the already scaled point p; `direction` is the bands' or the rings' direction,
 * whichever `type` uses. */
float texture_wave(vec3 p,
                   float distortion,
                   float detail,
                   float detail_scale,
                   float detail_roughness,
                   float phase,
                   int type,
                   int direction,
                   int profile)
{
  p = (p + 0.000001) * 0.999999;
  float n;
  if (type == WAVE_BANDS) {
    if (direction == WAVE_X) {
      n = p.x * 20.0;
    }
    else if (direction == WAVE_Y) {
      n = p.y * 20.0;
    }
    else if (direction == WAVE_Z) {
      n = p.z * 20.0;
    }
    else {
      n = (p.x + p.y + p.z) * 10.0;
    }
  }
  else {
    /* The distance from the axis: the axis' own coordinate drops out. */
    vec3 r = vec3((direction == WAVE_X) ? 0.0 : p.x,
                  (direction == WAVE_Y) ? 0.0 : p.y,
                  (direction == WAVE_Z) ? 0.0 : p.z);
    n = sqrt(r.x * r.x + r.y * r.y + r.z * r.z) * 20.0;
  }
  n += phase;
  if (distortion != 0.0) {
    float f = noise_fbm(texture_finite(p * detail_scale),
                        clamp(detail, 0.0, 15.0),
                        max(detail_roughness, 0.0),
                        2.0,
                        true);
    n += distortion * (f * 2.0 - 1.0);
  }
  n = texture_finite(n);
  /* Each profile lies in [0, 1], but GLSL gives sin no exact precision (it may return
   * 1.0000001) and from 2^23 on n + 0.5 rounds to the next integer (a triangle of 2): clamped. */
  if (profile == WAVE_SINE) {
    return clamp(0.5 + 0.5 * sin(n - 1.5707963267948966), 0.0, 1.0);
  }
  n /= 6.2831853071795864;
  if (profile == WAVE_SAW) {
    return clamp(n - floor(n), 0.0, 1.0);
  }
  return clamp(abs(n - floor(n + 0.5)) * 2.0, 0.0, 1.0);
}

/* The node: Color in .rgb (Fac, grey), Fac in .a. */
vec4 node_tex_wave(vec3 vector,
                   float scale,
                   float distortion,
                   float detail,
                   float detail_scale,
                   float detail_roughness,
                   float phase,
                   int type,
                   int direction,
                   int profile)
{
  vec3 p = texture_finite(texture_finite(vector) * scale);
  float f = texture_wave(p, distortion, detail, detail_scale, detail_roughness, phase, type, direction, profile);
  return vec4(f, f, f, f);
}

#endif /* PENUMBRA_LIB_NODES_TEXTURE_WAVE */
