// requires: lib/common.glsl lib/ssr.glsl
#ifndef PENUMBRA_LIB_CUBES
#define PENUMBRA_LIB_CUBES

/* Cube maps of the scene for what the screen does not hold (engine/frame/features/cubes.py):
 * a Sphere Light Probe's and the camera's, each six 90 deg faces drawn once a frame by the lit
 * pass, in one atlas (cube_color; cube_depth: each face's view depth along its forward axis,
 * 1e10 where nothing was drawn), a cube a block of 3 x 2 faces, one block a row. A traced ray
 * is marched through a cube as through the screen (lib/ssr.glsl ssr_march): its points, denser
 * near its start and offset anew each sample, are looked up in the direction they lie in from
 * the cube's centre, and the ray meets a surface where it passes from in front of the depth
 * there to behind it, no further behind than the surface's thickness (a ray that passed
 * behind an object the cube sees in front of it meets nothing there). The cube's depth gives
 * the parallax. frame.cube_params: (a face's side in texels, the longest ray, a surface's
 * thickness as a fraction of its depth, 0); cube_probe: a Sphere probe's centre (relative to
 * the origin) and its row (-1: none), cube_probe_influence the map into its influence (inside
 * under 1: the length, or for a box the largest component), cube_probe_shape (1 for a box, its
 * falloff, 0, 0); cube_camera: the camera's cube's centre and row (-1: none). */

#ifndef CUBE_STEPS
#  define CUBE_STEPS 24
#endif
#define CUBE_REFINE 5

#if CUBES
const vec3 cube_faces[18] = vec3[](CUBE_FACES);

/* The atlas pixel of direction ``q`` (from a cube's centre) in cube row ``row``, and q's
 * depth along that face's forward axis (``along``). */
vec2 cube_texel(vec3 q, float row, out float along)
{
  vec3 a = abs(q);
  int k = (a.x >= a.y && a.x >= a.z) ? (q.x >= 0.0 ? 0 : 1) : ((a.y >= a.z) ? (q.y >= 0.0 ? 2 : 3) : (q.z >= 0.0 ? 4 : 5));
  vec3 r = cube_faces[3 * k], u = cube_faces[3 * k + 1], f = cube_faces[3 * k + 2];
  along = dot(q, f);
  vec2 uv = vec2(dot(q, r), dot(q, u)) / max(along, 1e-30);
  float size = frame.cube_params.x;
  vec2 in_face = clamp((uv * 0.5 + 0.5) * size, vec2(0.0), vec2(size - 1.0));
  return vec2(float(k % 3), float(k / 3) + 2.0 * row) * size + in_face;
}

/* The cube's depth and our point's (``along``) at ray parameter ``t``. */
float cube_scene(vec3 C, float row, vec3 P, vec3 L, float t, out float along, out vec2 px)
{
  px = cube_texel(P + L * t - C, row, along);
  return texelFetch(cube_depth, ivec2(px), 0).r;
}

/* March from ``P`` (normal ``N``) along the unit ``L`` at most ``len`` world units through the
 * cube at ``C`` (row ``row``): 1 where it meets a surface there, with its ``radiance``, else 0. */
float cube_march(vec3 C, float row, vec3 P, vec3 N, vec3 L, float len, float jitter, out vec3 radiance)
{
  radiance = vec3(0.0);
  float thick = frame.cube_params.z;
  float along;
  vec2 px;
  /* The start must be seen from the cube's centre (within its thickness) to step out in front. */
  float scene = cube_scene(C, row, P, L, 0.0, along, px);
  bool front = along <= scene * (1.0 + thick);
  float t_prev = 0.0;
  for (int i = 0; i < CUBE_STEPS; i++) {
    float s = (float(i) + jitter) / float(CUBE_STEPS);
    float t = len * s * s;
    scene = cube_scene(C, row, P, L, t, along, px);
    bool behind = along > scene;
    if (behind && front) {
      float lo = t_prev, hi = t;
      for (int j = 0; j < CUBE_REFINE; j++) {
        float mid = 0.5 * (lo + hi);
        float a;
        vec2 p;
        float z = cube_scene(C, row, P, L, mid, a, p);
        if (a > z) {
          hi = mid;
        }
        else {
          lo = mid;
        }
      }
      float a_lo, a_hi;
      vec2 p_lo, p_hi;
      cube_scene(C, row, P, L, lo, a_lo, p_lo);
      float surface = cube_scene(C, row, P, L, hi, a_hi, p_hi);
      /* At the surface (not behind an object in front of the ray), and not the start's own. */
      vec3 q = P + L * hi - C;
      vec3 on = C + q * (surface / max(a_hi, 1e-30));
      bool own = abs(dot(on - P, N)) <= SSR_OWN * surface;
      if (a_hi - surface <= max(a_hi - a_lo, 0.0) + thick * surface && !own) {
        bool ok;
        radiance = ssr_fetch(cube_color, p_hi, ok);
        return ok ? 1.0 : 0.0;
      }
    }
    front = !behind;
    t_prev = t;
  }
  return 0.0;
}

/* How much a surface at ``P`` takes the Sphere probe's cube: 1 inside its influence, fading
 * over its falloff at the edge; 0 without one. */
float cube_probe_weight(vec3 P)
{
  if (frame.cube_probe.w < 0.0) {
    return 0.0;
  }
  vec3 l = (frame.cube_probe_influence * vec4(P, 1.0)).xyz;
  float d = (frame.cube_probe_shape.x > 0.5) ? max(max(abs(l.x), abs(l.y)), abs(l.z)) : length(l);
  return clamp((1.0 - d) / max(frame.cube_probe_shape.y, 1e-4), 0.0, 1.0);
}

/* The cubes' weight for the ray from ``P`` (normal ``N``) along ``L`` and the ``radiance`` it
 * meets: the Sphere probe's cube in its influence, the camera's for what that leaves. */
float cube_trace(vec3 P, vec3 N, vec3 L, float jitter, out vec3 radiance)
{
  float h = 0.0;
  vec3 hits = vec3(0.0), seen;
  float w = cube_probe_weight(P);
  if (w > 0.0) {
    h = w * cube_march(frame.cube_probe.xyz, frame.cube_probe.w, P, N, L, frame.cube_params.y, jitter, seen);
    hits = h * seen;
  }
  if (h < 1.0 && frame.cube_camera.w >= 0.0) {
    float m = (1.0 - h) *
              cube_march(frame.cube_camera.xyz, frame.cube_camera.w, P, N, L, frame.cube_params.y, jitter, seen);
    hits += m * seen;
    h += m;
  }
  radiance = (h > 0.0) ? hits / h : vec3(0.0);
  return h;
}
#endif

#endif /* PENUMBRA_LIB_CUBES */
