// requires: lib/common.glsl lib/depth_encoding.glsl lib/lights.glsl lib/lit_surface.glsl lib/shadow_filters.glsl
#ifndef PENUMBRA_LIB_INDIRECT_RSM
#define PENUMBRA_LIB_INDIRECT_RSM

/* One diffuse bounce from reflective shadow maps (Dachsbacher and Stamminger 2005, "Reflective
 * Shadow Maps"), with Light Paths > Diffuse Bounces at 1 (INDIRECT_RSM).
 *
 * Each texel of a light's map is the first surface the light meets along that texel: it is
 * lit, and as a Lambertian surface it sends the light on as a small area light. The atlas's
 * reflective targets hold its diffuse albedo (rsm_flux.rgb) and its world normal turned
 * towards the light (rsm_normal.xyz); its position comes from the map's depth and the tile's
 * projection, and the light's irradiance there from light_incident (lib/lights.glsl), so the
 * bounce follows the same light model as the direct light. The flux the texel reflects is
 *     Phi = albedo * E_perp * A_perp
 * with E_perp the irradiance across the light's rays and A_perp the texel's area across them
 * (the orthographic texel area texel^2 for suns; texel_per_distance^2 * z^2 / sqrt(1 + u^2 +
 * v^2) for perspective maps, at view depth z and tangent coordinates (u, v)): the cosine of
 * incidence cancels between the irradiance and the surface area the texel covers. A receiver
 * at P with normal N gets the irradiance
 *     dE = Phi * cos_s * cos_p / (pi * max(d^2, A_perp))
 * (cos_s at the sender, cos_p at the receiver, d the distance). The max() is the clamp of the
 * 1/d^2 singularity: no texel counts as nearer than the side of its own square, which bounds
 * what a texel gives a receiver touching it (a corner where two surfaces meet) at
 * albedo * E_perp * cos_s * cos_p / pi. Nothing between the texel and P is tested: RSM
 * ignores the occlusion of the bounce (light bounces through walls to points the sender does
 * not see), as the paper does.
 *
 * Sampling: RSM_SAMPLES texels per light and sample (the world's directions, each an estimate
 * of the one world, share them: RSM_SAMPLES / their count each, rounded up), on a per-pixel
 * rotation of a 3-D additive recurrence (Roberts' R3 sequence) indexed by frame.sample_index *
 * (the light's texels) + k,
 * so a frame's samples continue one low-discrepancy sequence and their average converges.
 * Around the pixel's projection c into its map (the paper's importance sampling: nearby
 * texels matter most), at radius r = R * u1 (u1 uniform) and a uniform angle: a density of
 * 1 / (2 pi r R) per texel, R = sqrt(2) * the map's side, with c clamped into the map so the
 * disk covers all of it; each texel's dE is divided by that density, so the estimate is
 * unbiased over the whole map, not only near c. Cube maps (point and area lights) mix that
 * strategy on the face the pixel lies in with a uniform choice of face and texel, half each,
 * weighted by the mixture's density (the balance heuristic), so senders on other faces count
 * too; a face's texels beyond its own quarter of directions (faces are widened for their
 * filters, so neighbours overlap) send nothing, so every direction counts once. A cascaded sun gathers from the cascade the pixel lies in.
 *
 * What is left out (biases): occlusion between sender and receiver; senders outside the maps
 * (maps are fitted to what the camera sees, so lit surfaces out of view send nothing; a
 * cascade's neighbours send nothing); casters pancaked onto a sun map's near plane are placed
 * there; the specular part of the bounce; light linking of the bounce. */

/* A 3-D hash of the pixel and the light (Jarzynski and Olano 2020, pcg3d). */
uvec3 rsm_hash(uvec3 v)
{
  v = v * 1664525u + 1013904223u;
  v.x += v.y * v.z;
  v.y += v.z * v.x;
  v.z += v.x * v.y;
  v ^= v >> 16u;
  v.x += v.y * v.z;
  v.y += v.z * v.x;
  v.z += v.x * v.y;
  return v;
}

/* The map of light L a receiver at P (view depth ``view_depth``) is importance-sampled in:
 * its single map, the cascade it lies in, or the cube face that sees it; -1: none. */
int rsm_home_tile(LightData L, vec3 P, float view_depth)
{
  if (L.shadow_mode == SHADOW_MODE_CUBE) {
    int f = cube_face(P - L.position);
    return (f < 4) ? L.tiles[f] : L.tiles_45[f - 4];
  }
  int t = L.tiles.x;
  if (L.shadow_mode == SHADOW_MODE_CASCADE) {
    for (int k = 1; k < 4; k++) {
      if (view_depth > L.cascade_splits[k - 1] && L.tiles[k] >= 0) {
        t = L.tiles[k];
      }
    }
  }
  return t;
}

/* Irradiance (per unit of L.color) at P, normal N, from texel st of map t of light L;
 * ``face``: the cube face map t is (-1: not a cube map). */
vec3 rsm_texel(LightData L, int t, int face, ivec2 st, vec3 P, vec3 N)
{
  ShadowTile T = shadow_tiles[t];
  ivec2 at = T.origin + st;
  float depth = decode_depth(texelFetch(shadow_atlas, at, 0));
  if (!(depth < 1.0)) {
    return vec3(0.0); /* nothing drawn there */
  }
  /* The texel's point in the light's view: its depth, then x, y through the projection (w
   * depends on z alone, and x, y on no other coordinate, for orthographic and off-centre
   * perspective maps alike). */
  float z = -(T.near + depth * (T.far - T.near));
  mat4 M = T.proj_tex;
  vec2 tex = (vec2(st) + 0.5) / float(T.size);
  float w = M[2][3] * z + M[3][3];
  vec2 xy = vec2((tex.x * w - M[2][0] * z - M[3][0]) / M[0][0], (tex.y * w - M[2][1] * z - M[3][1]) / M[1][1]);
  vec3 X = transpose(mat3(T.view)) * (vec3(xy, z) - T.view[3].xyz);
  if (face >= 0 && cube_face(X - L.position) != face) {
    return vec3(0.0); /* cube faces are widened for their filters: each direction counts once */
  }
  float area;
  if (M[2][3] == 0.0) {
    area = T.texel * T.texel;
  }
  else {
    vec2 tn = xy / -z;
    float tz = T.texel_per_distance * z;
    area = tz * tz * inversesqrt(1.0 + dot(tn, tn));
  }
  vec3 to_light;
  float irradiance;
  light_incident(L, X, to_light, irradiance);
  if (!(irradiance > 0.0)) {
    return vec3(0.0);
  }
  vec3 d = P - X;
  float d2 = dot(d, d);
  float inv = inversesqrt(max(d2, 1e-30));
  vec3 ns = texelFetch(rsm_normal, at, 0).xyz;
  float cos_s = max(dot(ns, d) * inv, 0.0);
  float cos_p = max(-dot(N, d) * inv, 0.0);
  vec3 albedo = texelFetch(rsm_flux, at, 0).rgb;
  return albedo * (irradiance * area * cos_s * cos_p / (M_PI * max(d2, area)));
}

/* Irradiance at P (normal N, view depth ``view_depth``) bounced once off the surfaces the maps
 * of the lights with maps (lights [0, frame.shadowed_count)) see: one sample's estimate. */
vec3 indirect_rsm(vec3 P, vec3 N, float view_depth)
{
  vec3 E = vec3(0.0);
  /* The directions of the world's light share one light's texels: each is one estimate of the
   * same light (the world's), so together they take RSM_SAMPLES, not that many each. */
  int world_lights = 0;
  for (int i = 0; i < frame.shadowed_count; i++) {
    world_lights += (lights[i].world != 0) ? 1 : 0;
  }
  int world_texels = max(1, (RSM_SAMPLES + max(world_lights, 1) - 1) / max(world_lights, 1));
  for (int i = 0; i < frame.shadowed_count; i++) {
    LightData L = lights[i];
    int texels = (L.world != 0) ? world_texels : RSM_SAMPLES;
    bool cube = L.shadow_mode == SHADOW_MODE_CUBE;
    int home = rsm_home_tile(L, P, view_depth);
    int home_face = cube ? cube_face(P - L.position) : -1;
    vec2 c = vec2(0.0);
    float R = 0.0;
    if (home >= 0) {
      ShadowTile T = shadow_tiles[home];
      vec4 t = T.proj_tex * (T.view * vec4(P, 1.0));
      float n = float(T.size);
      c = (t.w > 0.0) ? clamp(t.xy / t.w, 0.0, 1.0) * n : vec2(0.5 * n);
      R = 1.41421356 * n;
    }
    uvec3 rot = rsm_hash(uvec3(uvec2(gl_FragCoord.xy), uint(i)));
    vec3 sum = vec3(0.0);
    for (int k = 0; k < texels; k++) {
      /* R3: fractional parts of g / phi3^(1, 2, 3), phi3 = 1.2207440846, as 32-bit fixed point. */
      uint g = uint(frame.sample_index) * uint(texels) + uint(k);
      uvec3 x = rot + g * uvec3(3518319155u, 2882110345u, 2360945575u);
      vec3 u = vec3(x >> 8u) * (1.0 / 16777216.0);
      bool near = !cube || u.z < 0.5;
      int t = home, face = home_face;
      vec2 pos;
      if (near) {
        if (home < 0) {
          continue;
        }
        float r = R * u.x, phi = 2.0 * M_PI * u.y;
        pos = c + r * vec2(cos(phi), sin(phi));
      }
      else {
        face = min(int((u.z - 0.5) * 12.0), 5);
        t = (face < 4) ? L.tiles[face] : L.tiles_45[face - 4];
        if (t < 0) {
          continue;
        }
        pos = u.xy * float(shadow_tiles[t].size);
      }
      float n = float(shadow_tiles[t].size);
      if (pos.x < 0.0 || pos.y < 0.0 || pos.x >= n || pos.y >= n) {
        continue;
      }
      /* The density of this point per texel of map t: the disk around c (on the home map),
       * and with cube maps the uniform choice of face and texel. */
      float pdf = 0.0;
      if (t == home) {
        float r = distance(pos, c);
        pdf = (r < R) ? 1.0 / (2.0 * M_PI * max(r, 1e-6) * R) : 0.0;
      }
      if (cube) {
        pdf = 0.5 * pdf + 0.5 / (6.0 * n * n);
      }
      if (pdf > 0.0) {
        sum += rsm_texel(L, t, face, ivec2(pos), P, N) / pdf;
      }
    }
    E += L.color * (L.diffuse_factor / float(texels)) * sum;
  }
  return E;
}

/* One diffuse bounce on the surface ``s`` (lib/lit_surface.glsl), reflected by its diffuse
 * lobe(s). */
vec3 surface_bounce(Surface s)
{
  vec3 albedo = vec3(0.0);
  for (int k = 0; k < NODE_LOBES; k++) {
    albedo += s.lobe[k].weight * s.lobe[k].albedo;
  }
  return indirect_rsm(s.P, s.lobe[0].N, v_view_depth) / M_PI * albedo;
}

#endif /* PENUMBRA_LIB_INDIRECT_RSM */
