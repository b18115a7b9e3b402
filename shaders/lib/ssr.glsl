// requires: lib/common.glsl lib/world_env.glsl
#ifndef PENUMBRA_LIB_SSR
#define PENUMBRA_LIB_SSR

/* Reflections of the scene in glossy lobes (engine/frame/features/reflections.py): each sample
 * after a frame's first traces one ray per traced lobe and pixel, the lobe's GGX reflection of
 * a direction drawn anew each sample (Walter et al. 2007), in screen space against the view
 * depth of the camera's prepass (ssr_depth: distance along the camera axis, 0 where nothing
 * was drawn), stepping evenly in pixels with the depth interpolated in perspective (McGuire
 * and Mara 2014: 1/w and z/w are linear on the screen), the steps' offset drawn anew each
 * sample (Stachowiak 2015, stochastic screen-space reflections). A hit reads the frame's
 * image as its samples so far have made it (ssr_radiance, ``Film.mean_into``), so what the
 * ray meets is lit as the frame lights it, and the reflection converges with the samples.
 * A ray that leaves the screen or meets nothing gives no hit: the lobe keeps the world's
 * light (lit_world.glsl). frame.ssr_params: (the longest ray in world units, the thickness
 * taken for a surface as a fraction of its depth, 0, 0); frame.ssr_view and ssr_view_proj: the
 * camera the prepass was drawn through (the frame's, at the pixels' centres, where the image
 * ssr_radiance lies): the rays are traced through it, whatever this sample's pixel offset. */

#ifndef SSR
#  define SSR 0
#endif
#ifndef SSR_STEPS
#  define SSR_STEPS 32
#endif
#define SSR_REFINE 5      /* bisections between the last step in front and the first behind */
#define SSR_EDGE 0.05     /* hits fade out over this fraction of the screen at its edges */
#define SSR_START_PX 1.5  /* a reflected ray starts this many pixels from its surface (no self-hit) */
#define SSR_OWN 0.01      /* a hit this close to the start's plane (times its depth) is its own */

#ifndef REFRACTION
#  define REFRACTION 0
#endif

#ifndef TRANSMISSION
#  define TRANSMISSION 0
#endif

#ifndef PLANAR
#  define PLANAR 0
#endif

#ifndef CUBES
#  define CUBES 0
#endif

#if SSR || REFRACTION || TRANSMISSION || PLANAR || CUBES
uint ssr_hash(uint x)
{
  x ^= x >> 16u;
  x *= 0x7feb352du;
  x ^= x >> 15u;
  x *= 0x846ca68bu;
  x ^= x >> 16u;
  return x;
}

/* Three numbers in [0, 1) for this pixel, sample and lobe ``k``: a new set each sample. */
vec3 ssr_random(int k)
{
  uvec2 p = uvec2(gl_FragCoord.xy);
  uint h = ssr_hash(p.x * 1973u + ssr_hash(p.y * 9277u + ssr_hash(uint(frame.sample_index) * 26699u + uint(k))));
  uint a = ssr_hash(h + 1u), b = ssr_hash(h + 2u), c = ssr_hash(h + 3u);
  return vec3(uvec3(a, b, c) >> 8u) * (1.0 / 16777216.0);
}

/* A prepass's view depth at pixel ``p``, in channel ``channel`` of ``depth`` (clamped to the
 * screen: a fetch outside it is undefined). */
float ssr_scene(sampler2D depth, int channel, vec2 p, vec2 size)
{
  return texelFetch(depth, ivec2(clamp(p, vec2(0.0), size - 1.0)), 0)[channel];
}

/* The ray's view depth at fraction ``t`` of the screen segment (perspective-correct). */
float ssr_depth_at(vec4 q, float t)
{
  return -mix(q.x, q.y, t) / mix(q.z, q.w, t);
}

/* The fraction of the ray's length at fraction ``t`` of its screen segment: 1/w is linear on
 * the screen, so the ray's own parameter is t (1/w1) / (1/w at t). */
float ssr_fraction(vec4 q, float t)
{
  return t * q.w / mix(q.z, q.w, t);
}

/* March from ``P`` (world space, relative to the frame's origin) on a surface of normal ``N``
 * along the unit ``L``, at most ``len`` world units, through the camera (``view``,
 * ``view_proj``) that drew the view depth ``depth`` (in its channel ``channel``; at most
 * "infinitely" far, 1e10, or 0 where nothing was drawn): the hit's weight (0: none; fading to 0 at
 * the screen's edges) and its pixel ``hit``. ``thick``: the thickness taken for a surface as a
 * fraction of its depth. With ``own_check`` (a reflection: its own surface is in ``depth``) the
 * ray starts SSR_START_PX from it, and a surface point within SSR_OWN of its depth from the
 * start's tangent plane is the start's own surface (a ray that grazes it reads its depth
 * texels, taken at their centres, as in front of it), not a hit. */
float ssr_march(sampler2D depth,
                int channel,
                mat4 view,
                mat4 view_proj,
                float len,
                float thick,
                bool own_check,
                vec3 P,
                vec3 N,
                vec3 L,
                float jitter,
                out vec2 hit)
{
  hit = vec2(0.0);
  vec2 size = vec2(textureSize(depth, 0));
  vec3 v0 = (view * vec4(P, 1.0)).xyz;
  vec3 d = mat3(view) * L;
  vec3 nv = mat3(view) * N;
  if (frame.is_ortho == 0 && d.z > 0.0) {
    /* Towards the camera: the end stays in front of it. */
    len = min(len, (0.999 * -v0.z) / d.z);
  }
  if (!(len > 0.0) || !(-v0.z > 0.0)) {
    return 0.0;
  }
  vec4 h0 = view_proj * vec4(P, 1.0);
  vec4 h1 = view_proj * vec4(P + L * len, 1.0);
  if (!(h0.w > 0.0) || !(h1.w > 0.0)) {
    return 0.0;
  }
  vec2 s0 = (h0.xy / h0.w * 0.5 + 0.5) * size;
  vec2 ds = (h1.xy / h1.w * 0.5 + 0.5) * size - s0;
  /* (z/w at both ends, 1/w at both ends): the view depth is their ratio, linear on screen. */
  vec4 q = vec4(v0.z / h0.w, (v0.z + d.z * len) / h1.w, 1.0 / h0.w, 1.0 / h1.w);
  /* The segment clipped to the screen. */
  float t_end = 1.0;
  if (ds.x > 0.0) {
    t_end = min(t_end, (size.x - s0.x) / ds.x);
  }
  else if (ds.x < 0.0) {
    t_end = min(t_end, -s0.x / ds.x);
  }
  if (ds.y > 0.0) {
    t_end = min(t_end, (size.y - s0.y) / ds.y);
  }
  else if (ds.y < 0.0) {
    t_end = min(t_end, -s0.y / ds.y);
  }
  float pixels = length(ds) * t_end;
  float start_px = own_check ? SSR_START_PX : 0.0;
  if (!(pixels > start_px + 1.0)) {
    /* Along the view (within a pixel on the screen): a refracted ray meets what lies behind
     * its start at its start's pixel; a reflected one would meet its own surface. */
    float behind = ssr_scene(depth, channel, s0, size);
    bool inside = all(greaterThanEqual(s0, vec2(0.0))) && all(lessThan(s0, size));
    if (own_check || !inside || !(behind > 0.0) || behind < -v0.z * (1.0 - thick)) {
      return 0.0;
    }
    hit = s0;
    vec2 edge = min(s0, size - s0) / (SSR_EDGE * size);
    return clamp(min(edge.x, edge.y), 0.0, 1.0);
  }
  float t_start = start_px / length(ds);
  float dt = (t_end - t_start) / float(SSR_STEPS);
  float t_prev = t_start;
  for (int i = 0; i < SSR_STEPS; i++) {
    float t = t_start + dt * (float(i) + jitter);
    vec2 sp = s0 + ds * t;
    float scene = ssr_scene(depth, channel, sp, size);
    float ray = ssr_depth_at(q, t);
    if (scene > 0.0 && ray > scene) {
      float before = ssr_depth_at(q, t_prev);
      float thickness = max(ray - before, 0.0) + thick * scene;
      if (ray - scene <= thickness) {
        /* Between the last point in front of the surface and this one behind it. */
        float lo = t_prev, hi = t;
        for (int j = 0; j < SSR_REFINE; j++) {
          float mid = 0.5 * (lo + hi);
          float z = ssr_scene(depth, channel, s0 + ds * mid, size);
          if (z > 0.0 && ssr_depth_at(q, mid) > z) {
            hi = mid;
          }
          else {
            lo = mid;
          }
        }
        /* The crossing found, the ray must be at the surface there, not far behind it (a ray
         * that passed under a thin object and shows behind it on the screen), and the
         * surface not the start's own. */
        vec2 at_hit = s0 + ds * hi;
        float surface = ssr_scene(depth, channel, at_hit, size);
        float at = ssr_depth_at(q, hi);
        vec3 vr = v0 + d * (len * ssr_fraction(q, hi));
        vec3 vs = (frame.is_ortho != 0) ? vec3(vr.xy, -surface) : vr * (surface / max(at, 1e-30));
        bool own = own_check && abs(dot(vs - v0, nv)) <= SSR_OWN * surface;
        if (surface > 0.0 && at - surface <= thick * surface && !own) {
          hit = clamp(at_hit, vec2(0.0), size - 1.0);
          vec2 edge = min(at_hit, size - at_hit) / (SSR_EDGE * size);
          return clamp(min(edge.x, edge.y), 0.0, 1.0);
        }
      }
    }
    t_prev = t;
  }
  return 0.0;
}

/* The image ``image`` at pixel ``hit``, >= 0; ``ok`` false where it is not finite (never carry
 * a broken value into a reflection or a refraction). */
vec3 ssr_fetch(sampler2D image, vec2 hit, out bool ok)
{
  vec3 c = texelFetch(image, ivec2(hit), 0).rgb;
  ok = all(lessThan(abs(c), vec3(1e30)));
  return ok ? max(c, vec3(0.0)) : vec3(0.0);
}

/* The direction a traced lobe of normal ``N`` and Principled roughness ``rough`` reflects
 * ``V`` into this sample (a GGX normal drawn with ``xi``); the mirror direction where the
 * drawn one goes below the surface. */
vec3 ssr_direction(vec3 N, vec3 V, float rough, vec2 xi)
{
  vec3 R = reflect(-V, N);
  if (rough <= 0.0) {
    return R;
  }
  vec3 H = ggx_half_vector(xi, rough * rough, N);
  vec3 L = reflect(-V, H);
  return (dot(L, N) > 0.0) ? L : R;
}
#endif

#if SSR
/* A reflection (ssr_march through the prepass's camera, frame.ssr_*): the hit's weight and
 * ``radiance`` there, the frame's image so far. */
float ssr_trace(vec3 P, vec3 N, vec3 L, float jitter, out vec3 radiance)
{
  vec2 hit;
  float w = ssr_march(ssr_depth,
                      0,
                      frame.ssr_view, frame.ssr_view_proj, frame.ssr_params.x, frame.ssr_params.y, true, P, N, L, jitter, hit);
  bool ok = false;
  radiance = (w > 0.0) ? ssr_fetch(ssr_radiance, hit, ok) : vec3(0.0);
  return ok ? w : 0.0;
}
#endif

#endif /* PENUMBRA_LIB_SSR */
