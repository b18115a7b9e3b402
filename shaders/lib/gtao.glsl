// requires: lib/common.glsl lib/material.glsl
#ifndef PENUMBRA_LIB_GTAO
#define PENUMBRA_LIB_GTAO

#ifndef WORLD_AO
#  define WORLD_AO 0
#endif
#ifndef GTAO_UPSAMPLE
#  define GTAO_UPSAMPLE 0 /* 1: the lit pass, reading the half-resolution horizons */
#endif

#if WORLD_AO
/* Screen-space ground-truth ambient occlusion of the world's light (Jimenez, Wu, Pesce and
 * Jarabo 2016, "Practical Realtime Strategies for Accurate Indirect Occlusion"), per fragment
 * of the lit pass, over the camera depth prepass ``ao_depth`` (engine/frame/world/occlusion.py: the
 * view depth of every opaque and dithered surface through this sample's raster camera; 0 where
 * there is none).
 *
 * The hemisphere around the view direction V is cut into GTAO_SLICES planes through V, each
 * along a screen direction (rotated per pixel by interleaved gradient noise, Jimenez 2014, and
 * per sample by frame.ao_jitter). Along both halves of a slice, GTAO_STEPS depths at
 * quadratically growing distances (offset per pixel and sample) give the highest horizon
 * within frame.ao_distance (projected to pixels at the fragment's depth; samples fade out over
 * the last GTAO_FALLOFF of it). Thickness heuristic (the paper's): a sample below the horizon
 * found so far pulls it down by GTAO_THICKNESS, so a thin object in front does not hide all
 * that lies behind it. The horizons do not depend on the normal: ``gtao_visibility`` then
 * integrates the cosine-weighted visible arc between them analytically for a normal (the
 * paper's inner integral with the normal projected onto the slice), both lobes of a two-lobe
 * material from one march.
 *
 * Each slice's visible arc is divided by the summed unoccluded arcs of the same slices (a
 * ratio estimator of the cosine-weighted visibility): the expectation over the slice angle is
 * the paper's, and an unoccluded surface gets exactly 1 whatever its normal and however few
 * slices are taken. Everything is in units of the distance (positions divided by it), so the
 * result does not depend on the scene's scale. */

#  define GTAO_SLICES 3
#  define GTAO_STEPS 6
#  define GTAO_FALLOFF 0.25
#  define GTAO_THICKNESS 0.15
#  if GTAO_SLICES != 3
#    error "the half-resolution target packs three slices"
#  endif

/* Interleaved gradient noise (Jimenez 2014, "Next Generation Post Processing in Call of Duty:
 * Advanced Warfare"): float arithmetic on the pixel's integer coordinates. */
float gtao_noise(vec2 frag)
{
  vec2 p = floor(frag);
  return fract(52.9829189 * fract(dot(p, vec2(0.06711056, 0.00583715))));
}

/* The view-space position of view depth ``depth`` at pixel centre ``frag`` (frame.ao_*:
 * clip.x = P00 x + P02 z + P03, clip.w = P32 z + P33, for perspective and orthographic
 * cameras, off-axis shifts and sub-pixel jitter alike). */
vec3 gtao_view_position(vec2 frag, float depth)
{
  vec2 ndc = 2.0 * frag / frame.ao_viewport - 1.0;
  float z = -depth;
  float w = frame.ao_projection_w.z * z + frame.ao_projection_w.w;
  float x = (ndc.x * w - frame.ao_projection.z * z - frame.ao_projection_w.x) / frame.ao_projection.x;
  float y = (ndc.y * w - frame.ao_projection.w * z - frame.ao_projection_w.y) / frame.ao_projection.y;
  return vec3(x, y, z);
}

/* The view-space point the depth prepass shows at sub-pixel position ``pos`` (inside the
 * frame by half a pixel): the 2x2 texels around it interpolated where they lie on one plane
 * (1 / depth is affine on a plane's image in perspective, depth itself in orthographic), so a
 * step on a flat surface lands on it exactly and a plane never occludes itself; else the
 * nearest texel's own point (an edge, a crease), off the slice by up to half a pixel, with
 * ``weight`` falling from 1 on the slice's line (``dir`` through ``frag``) to 0 half a pixel
 * off it: its angle to V is another azimuth's, which at a grazing plane's silhouette would read
 * as occlusion. False where nothing is drawn. */
bool gtao_sample(vec2 pos, vec2 frag, vec2 dir, out vec3 S, out float weight)
{
  weight = 1.0;
  vec2 base = floor(pos - 0.5);
  vec2 f = pos - 0.5 - base;
  /* (i0, j1), (i1, j1), (i1, j0), (i0, j0) */
  vec4 d = textureGather(ao_depth, (base + 1.0) / frame.ao_viewport, 0);
  if (all(greaterThan(d, vec4(0.0)))) {
    bool ortho = frame.is_ortho != 0;
    vec4 q = ortho ? d : 1.0 / d;
    float big = max(max(abs(q.x), abs(q.y)), max(abs(q.z), abs(q.w)));
    if (abs(q.w + q.y - q.x - q.z) <= 1e-4 * big) {
      float v = mix(mix(q.w, q.z, f.x), mix(q.x, q.y, f.x), f.y);
      S = gtao_view_position(pos, ortho ? v : 1.0 / v);
      return true;
    }
  }
  vec2 texel = floor(pos);
  float depth = texelFetch(ao_depth, ivec2(texel), 0).r;
  vec2 off = texel + 0.5 - frag;
  weight = clamp(1.0 - 2.0 * abs(off.x * dir.y - off.y * dir.x), 0.0, 1.0);
  S = gtao_view_position(texel + 0.5, depth);
  return depth > 0.0;
}

struct GtaoHorizons {
  vec3 V;                    /* towards the camera, view space */
  vec3 t[GTAO_SLICES];       /* each slice's direction across V (towards its + half) */
  vec2 h[GTAO_SLICES];       /* horizon angles from V: x on the - half (<= 0), y on the + half */
  bool valid;
};

/* The frame of the horizons around view-space point ``P`` at pixel ``frag``: V and each
 * slice's direction t (rotated per noise ``cell`` and per sample), and in ``pixels`` how far
 * the occlusion reaches on screen (0: under a pixel, or a degenerate camera: unoccluded). The
 * noise cell is the half-resolution texel whose representative ``frag`` is, so the noise keeps
 * its pattern from cell to cell (interleaved gradient noise read every second pixel repeats in
 * stripes). */
GtaoHorizons gtao_frame(vec3 P, vec2 frag, vec2 cell, out float pixels)
{
  GtaoHorizons g;
  g.valid = false;
  g.V = (frame.is_ortho != 0) ? vec3(0.0, 0.0, 1.0) : -P * inversesqrt(max(dot(P, P), 1e-37));
  vec2 size = frame.ao_viewport;
  vec2 scale = vec2(frame.ao_projection.x * size.x, frame.ao_projection.y * size.y); /* pixels per unit at w 1, x2 */
  float w = frame.ao_projection_w.z * P.z + frame.ao_projection_w.w;
  pixels = 0.5 * frame.ao_distance * min(abs(scale.x), abs(scale.y)) / max(abs(w), 1e-37);
  pixels = min(pixels, length(size));
  if (!(frame.ao_distance > 0.0) || !(pixels >= 1.0) || !(abs(scale.x) > 0.0) || !(abs(scale.y) > 0.0)) {
    pixels = 0.0;
    return g;
  }
  float rotation = fract(gtao_noise(cell) + frame.ao_jitter.x);
  for (int i = 0; i < GTAO_SLICES; i++) {
    float phi = M_PI * (float(i) + rotation) / float(GTAO_SLICES);
    /* The slice's direction at P's depth: the screen direction lifted to view space. */
    vec3 d = vec3(cos(phi) / scale.x, sin(phi) / scale.y, 0.0);
    d -= g.V * dot(d, g.V);
    float dl = length(d);
    g.t[i] = (dl > 0.0) ? d / dl : vec3(1.0, 0.0, 0.0);
    g.h[i] = vec2(-0.5 * M_PI, 0.5 * M_PI);
  }
  g.valid = true;
  return g;
}

/* The horizons around view-space point ``P`` at pixel ``frag`` (noise ``cell``, gtao_frame). */
GtaoHorizons gtao_horizons(vec3 P, vec2 frag, vec2 cell)
{
  float pixels;
  GtaoHorizons g = gtao_frame(P, frag, cell, pixels);
  if (!g.valid) {
    return g; /* nothing within a pixel, or a degenerate camera: unoccluded */
  }
  float inv_radius = 1.0 / frame.ao_distance;
  vec2 size = frame.ao_viewport;
  float rotation = fract(gtao_noise(cell) + frame.ao_jitter.x);
  float offset = fract(pixel_hash(cell) + frame.ao_jitter.y);
  for (int i = 0; i < GTAO_SLICES; i++) {
    float phi = M_PI * (float(i) + rotation) / float(GTAO_SLICES);
    vec2 omega = vec2(cos(phi), sin(phi));
    vec2 horizon_cos = vec2(-1.0);
    for (int side = 0; side < 2; side++) {
      vec2 dir = (side == 0) ? -omega : omega;
      /* The steps stay inside the frame (by half a pixel): what lies beyond it is unknown. */
      vec2 room = mix(frag - 0.5, size - 0.5 - frag, step(0.0, dir)) / max(abs(dir), vec2(1e-6));
      float span = min(pixels, min(room.x, room.y));
      float h = -1.0;
      for (int j = 0; j < GTAO_STEPS && span >= 1.0; j++) {
        float u = (float(j) + offset) / float(GTAO_STEPS);
        vec2 pos = frag + dir * mix(1.0, span, u * u); /* a pixel away at least */
        vec3 S;
        float weight;
        if (!gtao_sample(pos, frag, dir, S, weight)) {
          continue; /* no surface there */
        }
        vec3 delta = (S - P) * inv_radius;
        float dist2 = dot(delta, delta);
        if (!(dist2 > 1e-12) || !(dist2 < 1.0)) {
          continue; /* out of reach (or the point itself) */
        }
        float dist = sqrt(dist2);
        float falloff = weight * clamp((1.0 - dist) / GTAO_FALLOFF, 0.0, 1.0);
        float c = mix(-1.0, dot(delta, g.V) / dist, falloff);
        h = (c > h) ? c : mix(h, c, GTAO_THICKNESS);
      }
      horizon_cos[side] = h;
    }
    g.h[i] = vec2(-acos(clamp(horizon_cos.x, -1.0, 1.0)), acos(clamp(horizon_cos.y, -1.0, 1.0)));
  }
  return g;
}

/* Half resolution. The horizons do not depend on the normal, so they are marched once per 2x2
 * pixels (shaders/ao_horizons.frag.glsl, engine/frame/world/occlusion.py), from one pixel of
 * each block, its representative (gtao_representative), into an RGBA32F target: each slice's
 * two angles packed in one float (11 bits each, exact in a float's 24-bit mantissa, rounded
 * towards the open side, so a plane's own horizon never occludes it) and the representative's
 * view depth (0: nothing drawn; horizons -1: unoccluded). A lit fragment takes the horizons of
 * its own block's representative where that lies within GTAO_UPSAMPLE_REACH of the occlusion
 * distance or GTAO_UPSAMPLE_PIXELS of the fragment's pixel size on its surface (a plane seen at
 * a grazing angle has neighbours far apart); else (a silhouette, a thin object) those of the
 * nearest in space of the four representatives around it (nearest-depth upsampling). It uses
 * them in that representative's frame (V, slice directions) and integrates them for its own
 * normals (a surface the prepass leaves out, alpha-blended, stays unoccluded: lit_world.glsl).
 * No fragment marches its own: the march's code in the lit pass cost a software rasteriser a
 * sixth of the pass even where it never ran. */
#  define GTAO_QUANTA 2047.0
#  define GTAO_UPSAMPLE_REACH 0.1
#  define GTAO_UPSAMPLE_PIXELS 3.0

/* The pixel that stands for half-resolution texel ``cell``: one of its block's four, picked by
 * a hash of the cell (a fixed corner would shift every horizon half a pixel the same way:
 * 0.01 less occlusion at the foot of a wall), inside the film. */
vec2 gtao_representative(vec2 cell)
{
  int k = int(pixel_hash(cell + 31.0) * 4.0) & 3;
  vec2 p = 2.0 * cell + vec2(float(k & 1), float(k >> 1));
  return min(p, frame.ao_viewport - 1.0) + 0.5;
}

float gtao_pack(vec2 h)
{
  vec2 q = ceil(clamp(vec2(-h.x, h.y) * (1.0 / M_PI), 0.0, 1.0) * GTAO_QUANTA);
  return q.x * 2048.0 + q.y;
}

vec2 gtao_unpack(float v)
{
  float qx = floor(v * (1.0 / 2048.0));
  return vec2(-qx, v - qx * 2048.0) * (M_PI / GTAO_QUANTA);
}

#  if GTAO_UPSAMPLE
/* Representative ``c`` of the half-resolution target, if its point lies nearer to ``P`` than
 * ``best`` (then lowered to its distance). */
bool gtao_nearer(ivec2 c, vec3 P, inout float best, inout vec4 rep, inout vec3 rep_P, inout vec2 rep_frag,
                 inout ivec2 rep_cell)
{
  vec4 r = texelFetch(ao_horizons, c, 0);
  if (!(r.w > 0.0)) {
    return false;
  }
  vec2 f = gtao_representative(vec2(c));
  vec3 S = gtao_view_position(f, r.w);
  float d = distance(S, P);
  if (!(d < best)) {
    return false;
  }
  best = d;
  rep = r;
  rep_P = S;
  rep_frag = f;
  rep_cell = c;
  return true;
}

GtaoHorizons gtao_horizons_upsampled(vec3 P, vec2 frag, float footprint)
{
  ivec2 last = textureSize(ao_horizons, 0) - 1;
  float best = max(GTAO_UPSAMPLE_REACH * frame.ao_distance, GTAO_UPSAMPLE_PIXELS * footprint);
  vec4 rep = vec4(0.0);
  vec3 rep_P = P;
  vec2 rep_frag = frag;
  ivec2 rep_cell = ivec2(0);
  /* The fragment's own block first (a plane's pixels take it, whatever the rounding of their
   * distances to the others); else the nearest of the four representatives around it. */
  if (!gtao_nearer(min(ivec2(floor(frag)) / 2, last), P, best, rep, rep_P, rep_frag, rep_cell)) {
    best = 3.4e38;
    ivec2 base = ivec2(floor((floor(frag) - 1.0) * 0.5));
    for (int k = 0; k < 4; k++) {
      gtao_nearer(clamp(base + ivec2(k & 1, k >> 1), ivec2(0), last), P, best, rep, rep_P, rep_frag, rep_cell);
    }
  }
  if (!(rep.w > 0.0)) {
    GtaoHorizons none;
    none.valid = false;
    return none; /* no surface of the prepass around (a blended surface over the world) */
  }
  float pixels;
  GtaoHorizons g = gtao_frame(rep_P, rep_frag, vec2(rep_cell), pixels);
  if (!(rep.x >= 0.0)) {
    g.valid = false;
    return g;
  }
  g.h[0] = gtao_unpack(rep.x);
  g.h[1] = gtao_unpack(rep.y);
  g.h[2] = gtao_unpack(rep.z);
  return g;
}
#  endif

/* One half of a slice's cosine-weighted arc from V to horizon angle h, for the normal
 * projected onto the slice at angle n from V (Jimenez et al. 2016, eq. 10). */
float gtao_arc(float h, float n)
{
  return 0.25 * (-cos(2.0 * h - n) + cos(n) + 2.0 * h * sin(n));
}

/* The world's cosine-weighted visibility in [0, 1] for unit view-space normal ``N`` (facing
 * the camera) under horizons ``g``. */
float gtao_visibility(GtaoHorizons g, vec3 N)
{
  if (!g.valid) {
    return 1.0;
  }
  float visible = 0.0, total = 0.0;
  for (int i = 0; i < GTAO_SLICES; i++) {
    vec3 t = g.t[i];
    vec3 axis = cross(t, g.V);
    vec3 Np = N - axis * dot(N, axis);
    float len = length(Np);
    if (!(len > 1e-6)) {
      continue; /* the normal is across the slice: it sees none of it */
    }
    float n = atan(dot(Np, t), max(dot(Np, g.V), 0.0));
    float h0 = max(g.h[i].x, n - 0.5 * M_PI);
    float h1 = min(g.h[i].y, n + 0.5 * M_PI);
    visible += len * (gtao_arc(h0, n) + gtao_arc(h1, n));
    total += len * (cos(n) + n * sin(n)); /* the unoccluded arc (horizons at n -/+ pi/2) */
  }
  float v = (total > 1e-6) ? visible / total : 1.0;
  return (v >= 0.0) ? min(v, 1.0) : (v < 0.0 ? 0.0 : 1.0); /* NaN -> 1 */
}

/* Specular occlusion from the diffuse visibility (Lagarde and de Rousiers 2014, "Moving
 * Frostbite to Physically Based Rendering", section 4.10.2): a rough lobe is occluded as the
 * diffuse, a sharp one seen head-on much less. ``alpha``: GGX roughness (squared). */
float gtao_specular(float visibility, float NdotV, float alpha)
{
  return clamp(pow(max(NdotV + visibility, 0.0), exp2(-16.0 * alpha - 1.0)) - 1.0 + visibility, 0.0, 1.0);
}
#endif

#endif /* PENUMBRA_LIB_GTAO */
