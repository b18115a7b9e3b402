// requires: lib/depth_encoding.glsl lib/lit_debug.glsl lib/material.glsl
#ifndef PENUMBRA_LIB_SHADOW_FILTERS
#define PENUMBRA_LIB_SHADOW_FILTERS

/* Shadow visibility of world point P for light L (1 = lit, 0 = shadowed).
 *
 * Every map is a square of shadow_atlas, shadow_tiles[i].size texels wide from texel
 * shadow_tiles[i].origin, described by shadow_tiles[i]: its light view, its projection to
 * texture space and its linear depth range. Stored depth is the distance along the light's view axis,
 * normalised to [near, far], so every light type compares and biases the same way.
 *
 * Bias is in texels of the map at the receiver, so one setting holds at every scene scale:
 *   normal offset  moves P along N by frame.normal_offset texels * sin(theta)
 *   constant       frame.constant_bias texels of depth
 *   slope-scaled   frame.slope_bias texels * tan(theta), tan clamped to 60 (89 degrees)
 *   receiver plane (frame.receiver_plane) every tap is compared with the depth the receiver's
 *                  own facet has at that texel's centre (its slope towards the light, from
 *                  the drawn triangle's normal): a tilted receiver read r texels away is
 *                  neither acne nor a reason to bias the whole kernel. Without it (or where
 *                  the facet faces away from the light) the slope bias grows with the
 *                  kernel: tan(theta) * max(1, r)
 * scaled per light by LightData.bias_scale (light.penumbra.bias_scale), and the normal offset
 * also by LightData.offset_scale (1/sqrt(samples) with jittered maps).
 *
 * Where the drawn facet turns away from the light (NfdotL <= 0) while the smooth normal faces
 * it, the point lies behind its own facet as seen from the light: on a closed smooth mesh it
 * is shadowed by the mesh itself, as a ray tracer draws it (the low-poly shadow terminator).
 * The angle-dependent terms (normal offset and slope bias, which grow without bound at the
 * terminator and would hide that self-shadowing) are left out there; only the constant bias
 * remains. Object > Shading > Shadow Terminator (lit.frag.glsl) then moves the point itself. */

int cube_face(vec3 d)
{
  vec3 a = abs(d);
  if (a.x >= a.y && a.x >= a.z) {
    return d.x >= 0.0 ? 0 : 1;
  }
  if (a.y >= a.z) {
    return d.y >= 0.0 ? 2 : 3;
  }
  return d.z >= 0.0 ? 4 : 5;
}

/* Texels per side of the map being read (ShadowTile.size), set by shadow_visibility. */
int tile_texels = 1;

/* 1 when ref is in front of the stored depth at integer texel st of the tile. Texels outside
 * the tile are lit: nothing was fitted to cast there. */
float shadow_tap(ivec2 origin, ivec2 st, float ref)
{
  int size = tile_texels;
  if (st.x < 0 || st.y < 0 || st.x >= size || st.y >= size) {
    return 1.0;
  }
  float stored = decode_depth(texelFetch(shadow_atlas, origin + st, 0));
  return (ref <= stored) ? 1.0 : 0.0;
}

float shadow_depth_at(ivec2 origin, ivec2 st)
{
  int size = tile_texels;
  st = clamp(st, ivec2(0), ivec2(size - 1));
  return decode_depth(texelFetch(shadow_atlas, origin + st, 0));
}

/* The reference depth at texel t: ``ref`` at the lookup point st, moved along the receiver's
 * plane (``grad``: its normalised depth per texel) to the texel's centre. */
float plane_ref(ivec2 t, vec2 st, float ref, vec2 grad)
{
  return ref + dot(grad, vec2(t) + 0.5 - st);
}

/* Bilinear-weighted 2x2 comparison: exactly what a linear-filtered compare sampler returns. */
float shadow_bilinear(ivec2 origin, vec2 st, float ref, vec2 grad)
{
  vec2 p = st - 0.5;
  vec2 f = fract(p);
  ivec2 b = ivec2(floor(p));
  float s00 = shadow_tap(origin, b, plane_ref(b, st, ref, grad));
  float s10 = shadow_tap(origin, b + ivec2(1, 0), plane_ref(b + ivec2(1, 0), st, ref, grad));
  float s01 = shadow_tap(origin, b + ivec2(0, 1), plane_ref(b + ivec2(0, 1), st, ref, grad));
  float s11 = shadow_tap(origin, b + ivec2(1, 1), plane_ref(b + ivec2(1, 1), st, ref, grad));
  return mix(mix(s00, s10, f.x), mix(s01, s11, f.x), f.y);
}

/* Disk offset i of this pixel. Each sample of a frame reads another pixel's disk (the pattern
 * shifted by a hash of the sample's frame.alpha_offset), so a frame's samples average
 * independent rotations and a sample needs only its share of the taps. */
vec2 disk_sample(int i)
{
  uint h = uint(frame.alpha_offset * 65536.0) * 0x9E3779B1u;
  ivec2 pix = (ivec2(gl_FragCoord.xy) + ivec2(h >> 16u, h >> 8u)) % JITTER_SIZE;
  vec4 pair = texelFetch(jitter_tex, ivec3(pix, i / 2), 0);
  return ((i & 1) == 0) ? pair.xy : pair.zw;
}

/* Disk PCF of radius r texels with the per-pixel jittered samples. With EARLY_OUT, the outer
 * ring (the first 8 samples) decides alone when it agrees (fully lit or fully shadowed). */
float shadow_disk(ivec2 origin, vec2 st, float ref, float r, vec2 grad)
{
  float lit = 0.0;
  for (int i = 0; i < 8; i++) {
    ivec2 t = ivec2(floor(st + disk_sample(i) * r));
    lit += shadow_tap(origin, t, plane_ref(t, st, ref, grad));
  }
#if EARLY_OUT
  if (lit == 0.0 || lit == 8.0) {
    return lit / 8.0;
  }
#endif
  for (int i = 8; i < DISK_SAMPLES; i++) {
    ivec2 t = ivec2(floor(st + disk_sample(i) * r));
    lit += shadow_tap(origin, t, plane_ref(t, st, ref, grad));
  }
  /* A division need not be correctly rounded (x * rcp(y) on some GPUs): n / n may exceed 1. */
  return min(lit / float(DISK_SAMPLES), 1.0);
}

/* The map of light L that holds world point P (an index of shadow_tiles), or -1: none (no
 * map, or a cube face with no caster in reach, which was not rendered). */
int shadow_tile(LightData L, vec3 P)
{
  int mode = L.shadow_mode;
  if (mode == SHADOW_MODE_NONE) {
    return -1;
  }
  int tile;
  if (mode == SHADOW_MODE_SINGLE) {
    tile = L.tiles.x;
  }
  else if (mode == SHADOW_MODE_CASCADE) {
    /* The slice of the visible depth range P lies in (view depth along the camera axis). In
     * the band before a split both maps cover P: the next one takes over with a probability
     * that rises across the band (a per-pixel hash, moved on every sample), so the seam is a
     * gradual change of texel size instead of a line. */
    float d = dot(P - frame.camera_position, frame.camera_forward);
    vec4 ends = L.cascade_splits;
    int c = (d < ends.x) ? 0 : (d < ends.y) ? 1 : (d < ends.z) ? 2 : 3;
    if (c < 3) {
      float band = L.cascade_blend[c];
      float into = (band > 0.0) ? (d - (ends[c] - band)) / band : 0.0;
      if (into > 0.0 && fract(pixel_hash(gl_FragCoord.xy + 61.0) + frame.alpha_offset) < into) {
        c += 1;
      }
    }
    tile = L.tiles[c];
#if DEBUG_LIT
    if (debug_cascade == 0.0 && tile >= 0) {
      debug_cascade = float(c + 1);
    }
#endif
  }
  else {
    int face = cube_face(P - L.position);
    tile = (face < 4) ? L.tiles[face] : L.tiles_45[face - 4];
  }
  return tile;
}

/* How far P lies behind the first surface light L's map holds along its axis towards P (world
 * units: the thickness of what the light crosses to reach P from behind), or -1 where no map
 * holds P. The nearest texel, no bias: what a back face reads (features/subsurface.py). */
float shadow_thickness(LightData L, vec3 P)
{
  int tile = shadow_tile(L, P);
  if (tile < 0) {
    return -1.0;
  }
  ShadowTile T = shadow_tiles[tile];
  vec4 vp = T.view * vec4(P, 1.0);
  vec4 t = T.proj_tex * vp;
  if (t.w <= 0.0) {
    return -1.0;
  }
  ivec2 st = ivec2(floor(t.xy / t.w * float(T.size)));
  if (any(lessThan(st, ivec2(0))) || any(greaterThanEqual(st, ivec2(T.size)))) {
    return -1.0;
  }
  float stored = T.near + decode_depth(texelFetch(shadow_atlas, T.origin + st, 0)) * (T.far - T.near);
  return max(-vp.z - stored, 0.0);
}

/* ``filter_id`` is a literal at every call (FILTER_*), so each call compiles to its one filter:
 * lights sampled over their extent use PCSS with their per-sample size, the others the
 * scene's filter. */
float shadow_visibility(LightData L, vec3 P, vec3 N, vec3 Nf, float NdotL, float NfdotL, const int filter_id)
{
  int tile = shadow_tile(L, P);
  if (tile < 0) {
    return 1.0; /* no map, or a cube face with no caster in reach (not rendered) */
  }
  ShadowTile T = shadow_tiles[tile];
  float near = T.near, far = T.far;
  float depth_scale = 1.0 / (far - near);
  float bias_scale = L.bias_scale;

  float cos_t = clamp(NdotL, 1e-4, 1.0);
  float sin_t = sqrt(1.0 - cos_t * cos_t);
  float tan_t = min(sin_t / cos_t, 60.0);
  if (NfdotL <= 0.0) {
    sin_t = 0.0; /* the facet turns away from the light: see above */
    tan_t = 0.0;
  }
  float dist = max(-(T.view * vec4(P, 1.0)).z, 0.0);
  float texel = T.texel + T.texel_per_distance * dist;

  vec3 Po = P + N * (frame.normal_offset * bias_scale * L.offset_scale * texel * sin_t);
  vec4 vp = T.view * vec4(Po, 1.0);
  vec4 t = T.proj_tex * vp;
  if (t.w <= 0.0) {
    return 1.0;
  }
  vec2 uv = t.xy / t.w;
#if DEBUG_LIT
  {
    /* The map's texel coordinates st = size * t.xy / t.w, differentiated along the pixel's
     * footprint: texels per pixel = sqrt(|det d(st)/d(x, y)|). */
    mat4 M = T.proj_tex * T.view;
    vec4 tx = M * vec4(debug_dPdx, 0.0), ty = M * vec4(debug_dPdy, 0.0);
    vec2 sx = float(T.size) * (tx.xy * t.w - t.xy * tx.w) / (t.w * t.w);
    vec2 sy = float(T.size) * (ty.xy * t.w - t.xy * ty.w) / (t.w * t.w);
    float density = sqrt(abs(sx.x * sy.y - sx.y * sy.x));
    debug_density = (debug_density > 0.0) ? min(debug_density, density) : density;
  }
#endif
  float receiver = -vp.z;
  float constant_bias = frame.constant_bias * bias_scale * texel;
  float slope_bias = frame.slope_bias * bias_scale * texel * tan_t;
  /* The receiver's plane in the map: its normalised depth per texel along s and t. */
  vec2 grad = vec2(0.0);
  float grows = 1.0; /* how the slope bias grows with the kernel's radius */
  if (frame.receiver_plane != 0) {
    vec3 nl = mat3(T.view) * Nf;
    if (nl.z > 1.0 / 60.0) {
      grad = (nl.xy / nl.z) * (texel * depth_scale);
      grows = 0.0;
    }
  }
  /* Reference depth at the lookup point for a filter that reads texels up to r away. */
#define SHADOW_REF(r) ((receiver - constant_bias - slope_bias * max(1.0, grows * (r)) - near) * depth_scale)
  if (SHADOW_REF(0.0) >= 1.0) {
    return 1.0;
  }
  int size = T.size;
  tile_texels = size;
  ivec2 origin = T.origin;
  vec2 st = uv * float(size);

  if (filter_id == FILTER_NONE) {
    ivec2 t = ivec2(floor(st));
    return shadow_tap(origin, t, plane_ref(t, st, SHADOW_REF(0.0), grad));
  }
  if (filter_id == FILTER_HARDWARE) {
    return shadow_bilinear(origin, st, SHADOW_REF(1.0), grad);
  }
#if SHADOW_FILTER == FILTER_PCF
  if (filter_id == FILTER_PCF) {
  /* Separable Gaussian weights compiled in as constants, so both loops unroll. */
  const float w[2 * PCF_RADIUS + 2] = float[](PCF_WEIGHTS_LIST, 0.0); /* one zero past the end */
  float spacing = frame.pcf_spacing;
  float ref = SHADOW_REF(float(PCF_RADIUS) * spacing);
  float lit = 0.0;
#  if PCF_GATHER
  {
  /* Taps one texel apart: each textureGather reads a 2x2 block, so an NxN kernel takes
   * ceil(N/2)^2 fetches. Gather order: (x0, y1), (x1, y1), (x1, y0), (x0, y0). The block past
   * the kernel's last row/column gets the zero weight. */
  ivec2 c = ivec2(floor(st));
  vec2 inv_atlas = 1.0 / vec2(textureSize(shadow_atlas, 0));
  for (int by = -PCF_RADIUS; by <= PCF_RADIUS; by += 2) {
    for (int bx = -PCF_RADIUS; bx <= PCF_RADIUS; bx += 2) {
      ivec2 b = c + ivec2(bx, by);
      vec4 d = textureGather(shadow_atlas, (vec2(origin + b) + 1.0) * inv_atlas);
      /* Texels outside the tile are lit (negative coordinates wrap to huge unsigned ones). */
      bvec4 in_x = lessThan(uvec4(ivec4(b.x, b.x + 1, b.x + 1, b.x)), uvec4(size));
      bvec4 in_y = lessThan(uvec4(ivec4(b.y + 1, b.y + 1, b.y, b.y)), uvec4(size));
      vec4 inside = vec4(in_x) * vec4(in_y);
      /* Each texel's reference on the receiver's plane (centres of the gathered 2x2 block). */
      vec4 refs = ref + grad.x * (vec4(b.x, b.x + 1, b.x + 1, b.x) + 0.5 - st.x) +
                  grad.y * (vec4(b.y + 1, b.y + 1, b.y, b.y) + 0.5 - st.y);
      vec4 tap = mix(vec4(1.0), vec4(lessThanEqual(refs, d)), inside);
      vec4 wx = vec4(w[bx + PCF_RADIUS], w[bx + PCF_RADIUS + 1], w[bx + PCF_RADIUS + 1], w[bx + PCF_RADIUS]);
      vec4 wy = vec4(w[by + PCF_RADIUS + 1], w[by + PCF_RADIUS + 1], w[by + PCF_RADIUS], w[by + PCF_RADIUS]);
      lit += dot(tap, wx * wy);
    }
  }
  return min(lit, 1.0); /* the weights sum to 1 up to rounding (and fused multiply-adds) */
  }
#  endif
  for (int y = -PCF_RADIUS; y <= PCF_RADIUS; y++) {
    float row = 0.0;
    for (int x = -PCF_RADIUS; x <= PCF_RADIUS; x++) {
      ivec2 t = ivec2(floor(st + vec2(x, y) * spacing));
      row += w[x + PCF_RADIUS] * shadow_tap(origin, t, plane_ref(t, st, ref, grad));
    }
    lit += w[y + PCF_RADIUS] * row;
  }
  return min(lit, 1.0); /* the weights sum to 1 up to rounding (and fused multiply-adds) */
  }
#endif
  if (filter_id == FILTER_JITTER) {
    float r = frame.filter_radius;
    return shadow_disk(origin, st, SHADOW_REF(r), r, grad);
  }
  /* FILTER_PCSS */
  /* 1. Blocker search: average depth of the texels that occlude P, over the region a light of
   *    this size can shadow P from. 2. Penumbra width from similar triangles: sun
   *    w = (d_r - d_b) * 2 tan(angle / 2); local light w = 2 r (d_r - d_b) / d_b.
   *    3. Disk PCF of that width: hard at contact, soft far from the caster, as in Cycles. */
  bool sun = L.type == LIGHT_SUN;
  float max_r = min(frame.max_filter_radius, max(32.0, 0.25 * float(size)));
  float search_world = sun ? (receiver - near) * 2.0 * L.sun_tan_half_angle :
                             2.0 * L.shadow_radius * (receiver - near) / max(receiver, 1e-30);
  float search = clamp(0.5 * search_world / texel, 1.0, max_r);
#if PILOT_SAMPLE
  /* A frame's pilot sample (engine/frame/features/settling.py) is kept only where every moving light's
   * visibility is the same from all of the light: there one bilinear lookup reads it. */
  return shadow_bilinear(origin, st, SHADOW_REF(1.0), grad);
#endif
#if SETTLE_TEST
  {
    /* The settle test (engine/frame/features/settling.py), with the light at its whole size: whether
     * every point of the light, on every shift of the map, sees P the same. The map was drawn
     * from the light's centre, so the region it must show is the light's half width
     * (PCSS's blocker search region) around P, plus a texel and a half for the maps'
     * sub-texel shifts and the bilinear lookup. 1: no texel of it occludes P (lit from
     * everywhere), 0: every texel does (the casters cover every way to the light), -1: it
     * may change. A region past SETTLE_REACH texels, or leaving a local light's map, may
     * change; beyond SETTLE_GRID texels the grid samples it every reach / SETTLE_GRID
     * texels. */
    float reach = 0.5 * search_world / texel + 1.5;
    if (!(reach <= float(SETTLE_REACH))) {
      return -1.0;
    }
    int n = int(ceil(min(reach, float(SETTLE_GRID))));
    float spacing = reach / float(n);
    float ref = SHADOW_REF(reach);
    float lit = 0.0, taps = 0.0;
    for (int y = -n; y <= n; y++) {
      for (int x = -n; x <= n; x++) {
        ivec2 t = ivec2(floor(st + vec2(x, y) * spacing));
        if (!sun && (any(lessThan(t, ivec2(0))) || any(greaterThanEqual(t, ivec2(size))))) {
          return -1.0;
        }
        lit += shadow_tap(origin, t, plane_ref(t, st, ref, grad));
        taps += 1.0;
        if (lit > 0.0 && lit < taps) {
          return -1.0; /* some of it occludes, some does not */
        }
      }
    }
    return (lit == taps) ? 1.0 : (lit == 0.0) ? 0.0 : -1.0;
  }
#endif
  if (L.jittered != 0 && 0.5 * search_world <= texel) {
    /* This sample's penumbra is under two texels wide here (a light without size: none):
     * one bilinear lookup, which the frame's jittered maps average into the edge filtered
     * over about a texel, instead of a noisy disk of half a texel. */
    return shadow_bilinear(origin, st, SHADOW_REF(1.0), grad);
  }
  float ref = SHADOW_REF(search);
  float blockers = 0.0, blocker_sum = 0.0;
  for (int i = 0; i < DISK_SAMPLES; i++) {
    ivec2 t = ivec2(floor(st + disk_sample(i) * search));
    float d = shadow_depth_at(origin, t);
    if (d < plane_ref(t, st, ref, grad)) {
      blockers += 1.0;
      blocker_sum += d;
    }
  }
  if (blockers == 0.0) {
    return 1.0;
  }
  float blocker = near + (blocker_sum / blockers) * (far - near);
  float width = sun ? (receiver - blocker) * 2.0 * L.sun_tan_half_angle :
                      2.0 * L.shadow_radius * (receiver - blocker) / max(blocker, 1e-30);
  float r = clamp(0.5 * width / texel, 0.5, max_r);
  return shadow_disk(origin, st, SHADOW_REF(r), r, grad);
#undef SHADOW_REF
}

#endif /* PENUMBRA_LIB_SHADOW_FILTERS */
