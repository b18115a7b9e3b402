// requires: nodes/common.glsl nodes/texture_hash.glsl
#ifndef PENUMBRA_LIB_NODES_TEXTURE_VORONOI
#define PENUMBRA_LIB_NODES_TEXTURE_VORONOI

/* Blender's Voronoi Texture node: cellular noise after Steven Worley, "A Cellular Texture Basis
 * Function", SIGGRAPH 1996 (one jittered feature point per unit cell, the 3^d neighbourhood
 * searched), with Blender's outputs and options:
 * - features F1, F2, Smooth F1 (a smooth minimum over the 5^d neighbourhood, after Inigo Quilez,
 *   "Smooth Voronoi", 2014), Distance to Edge (Quilez, "Voronoi edges", 2012, with the -1..1
 *   window) and N-Sphere Radius;
 * - metrics Euclidean, Manhattan, Chebychev and Minkowski (exponent); 1 to 4 dimensions;
 * - Randomness (jitter of the feature points), and Blender's fractal octaves (Detail, Roughness,
 *   Lacunarity, Normalize) as its fractal_voronoi_x_fx / fractal_voronoi_distance_to_edge.
 *
 * Feature points: 1D hashes the float cell coordinate (lookup3 of its bits). For 2-4D, Blender
 * up to 4.5 hashes the float cell coordinates (VORONOI_HASH_FLOAT) and Blender 5 hashes integer
 * cell coordinates with PCG (VORONOI_HASH_INT): the two place different points.
 *
 * Out-of-range cells convert to int as x86 does (INT_MIN); a non-finite coordinate reads as 0
 * (Blender would return NaN), so every output is finite. */

/* Voronoi Texture node `feature`. */
#define VORONOI_F1 0
#define VORONOI_F2 1
#define VORONOI_SMOOTH_F1 2
#define VORONOI_DISTANCE_TO_EDGE 3
#define VORONOI_N_SPHERE_RADIUS 4

/* Voronoi Texture node `distance`. */
#define VORONOI_EUCLIDEAN 0
#define VORONOI_MANHATTAN 1
#define VORONOI_CHEBYCHEV 2
#define VORONOI_MINKOWSKI 3

/* How cells are hashed (Blender's version). */
#define VORONOI_HASH_FLOAT 0
#define VORONOI_HASH_INT 1

#define VORONOI_FLT_MAX 3.402823466e+38

int voronoi_cell_int(float f)
{
  return (abs(f) < 2147483648.0) ? int(f) : (-2147483647 - 1);
}

ivec2 voronoi_cell_int(vec2 f)
{
  return ivec2(voronoi_cell_int(f.x), voronoi_cell_int(f.y));
}

ivec3 voronoi_cell_int(vec3 f)
{
  return ivec3(voronoi_cell_int(f.x), voronoi_cell_int(f.y), voronoi_cell_int(f.z));
}

ivec4 voronoi_cell_int(vec4 f)
{
  return ivec4(voronoi_cell_int(f.x), voronoi_cell_int(f.y), voronoi_cell_int(f.z), voronoi_cell_int(f.w));
}

/* Neighbour n of a (2r+1)^d window, x fastest (Blender's loop order). */
ivec2 voronoi_offset(int n, int r, ivec2 like)
{
  int s = 2 * r + 1;
  return ivec2(n % s, (n / s) % s) - r;
}

ivec3 voronoi_offset(int n, int r, ivec3 like)
{
  int s = 2 * r + 1;
  return ivec3(n % s, (n / s) % s, (n / (s * s)) % s) - r;
}

ivec4 voronoi_offset(int n, int r, ivec4 like)
{
  int s = 2 * r + 1;
  return ivec4(n % s, (n / s) % s, (n / (s * s)) % s, (n / (s * s * s)) % s) - r;
}

/* The feature point's jitter in [0, 1]^d, and the cell colour. */
vec2 voronoi_jitter(vec2 cell_f, ivec2 cell_i, ivec2 o, int hash_mode)
{
  return (hash_mode == VORONOI_HASH_INT) ? hash_ivec2_to_vec2(cell_i + o) : hash_vec2_to_vec2(cell_f + vec2(o));
}

vec3 voronoi_jitter(vec3 cell_f, ivec3 cell_i, ivec3 o, int hash_mode)
{
  return (hash_mode == VORONOI_HASH_INT) ? hash_ivec3_to_vec3(cell_i + o) : hash_vec3_to_vec3(cell_f + vec3(o));
}

vec4 voronoi_jitter(vec4 cell_f, ivec4 cell_i, ivec4 o, int hash_mode)
{
  return (hash_mode == VORONOI_HASH_INT) ? hash_ivec4_to_vec4(cell_i + o) : hash_vec4_to_vec4(cell_f + vec4(o));
}

vec3 voronoi_color(vec2 cell_f, ivec2 cell_i, ivec2 o, int hash_mode)
{
  return (hash_mode == VORONOI_HASH_INT) ? hash_ivec2_to_vec3(cell_i + o) : hash_vec2_to_vec3(cell_f + vec2(o));
}

vec3 voronoi_color(vec3 cell_f, ivec3 cell_i, ivec3 o, int hash_mode)
{
  return (hash_mode == VORONOI_HASH_INT) ? hash_ivec3_to_vec3(cell_i + o) : hash_vec3_to_vec3(cell_f + vec3(o));
}

vec3 voronoi_color(vec4 cell_f, ivec4 cell_i, ivec4 o, int hash_mode)
{
  return (hash_mode == VORONOI_HASH_INT) ? hash_ivec4_to_vec3(cell_i + o) : hash_vec4_to_vec3(cell_f + vec4(o));
}

float voronoi_sum(vec2 v)
{
  return v.x + v.y;
}

float voronoi_sum(vec3 v)
{
  return v.x + v.y + v.z;
}

float voronoi_sum(vec4 v)
{
  return v.x + v.y + v.z + v.w;
}

float voronoi_max(vec2 v)
{
  return max(v.x, v.y);
}

float voronoi_max(vec3 v)
{
  return max(v.x, max(v.y, v.z));
}

float voronoi_max(vec4 v)
{
  return max(v.x, max(v.y, max(v.z, v.w)));
}

vec4 voronoi_position(float p)
{
  return vec4(0.0, 0.0, 0.0, p);
}

vec4 voronoi_position(vec2 p)
{
  return vec4(p, 0.0, 0.0);
}

vec4 voronoi_position(vec3 p)
{
  return vec4(p, 0.0);
}

vec4 voronoi_position(vec4 p)
{
  return p;
}

/* One octave's result: distance, colour, position (1D: in .w). */
struct VoronoiOctave {
  float distance;
  vec3 color;
  vec4 position;
};

/* ---- 1D: float cells, lookup3 of the cell coordinate, |a - b| whatever the metric ---- */

float voronoi_distance(float a, float b, int metric, float exponent)
{
  return abs(b - a);
}

float voronoi_point1(float cell, float o, float randomness)
{
  return o + hash_float_to_float(cell + o) * randomness;
}

VoronoiOctave voronoi_f1(float coord, int metric, float exponent, float randomness, int hash_mode)
{
  float cell = floor(coord);
  float local = coord - cell;
  float min_d = VORONOI_FLT_MAX;
  float target_o = 0.0;
  float target_p = 0.0;
  for (int i = -1; i <= 1; i++) {
    float o = float(i);
    float p = voronoi_point1(cell, o, randomness);
    float d = abs(local - p);
    if (d < min_d) {
      target_o = o;
      min_d = d;
      target_p = p;
    }
  }
  return VoronoiOctave(min_d, hash_float_to_vec3(cell + target_o), voronoi_position(target_p + cell));
}

VoronoiOctave voronoi_smooth_f1(
    float coord, int metric, float exponent, float randomness, float smoothness, int hash_mode)
{
  float cell = floor(coord);
  float local = coord - cell;
  float smooth_d = 0.0;
  float smooth_p = 0.0;
  vec3 smooth_c = vec3(0.0);
  float h = -1.0;
  for (int i = -2; i <= 2; i++) {
    float o = float(i);
    float p = voronoi_point1(cell, o, randomness);
    float d = abs(local - p);
    h = (h == -1.0) ? 1.0 : smoothstep(0.0, 1.0, 0.5 + 0.5 * (smooth_d - d) / smoothness);
    float correction = smoothness * h * (1.0 - h);
    smooth_d = mix(smooth_d, d, h) - correction;
    correction /= 1.0 + 3.0 * smoothness;
    smooth_c = mix(smooth_c, hash_float_to_vec3(cell + o), h) - correction;
    smooth_p = mix(smooth_p, p, h) - correction;
  }
  return VoronoiOctave(smooth_d, smooth_c, voronoi_position(cell + smooth_p));
}

VoronoiOctave voronoi_f2(float coord, int metric, float exponent, float randomness, int hash_mode)
{
  float cell = floor(coord);
  float local = coord - cell;
  float d1 = VORONOI_FLT_MAX;
  float d2 = VORONOI_FLT_MAX;
  float o1 = 0.0, p1 = 0.0, o2 = 0.0, p2 = 0.0;
  for (int i = -1; i <= 1; i++) {
    float o = float(i);
    float p = voronoi_point1(cell, o, randomness);
    float d = abs(local - p);
    if (d < d1) {
      d2 = d1;
      d1 = d;
      o2 = o1;
      o1 = o;
      p2 = p1;
      p1 = p;
    }
    else if (d < d2) {
      d2 = d;
      o2 = o;
      p2 = p;
    }
  }
  return VoronoiOctave(d2, hash_float_to_vec3(cell + o2), voronoi_position(p2 + cell));
}

float voronoi_distance_to_edge(float coord, float randomness, int hash_mode)
{
  float cell = floor(coord);
  float local = coord - cell;
  float mid = hash_float_to_float(cell) * randomness;
  float left = -1.0 + hash_float_to_float(cell - 1.0) * randomness;
  float right = 1.0 + hash_float_to_float(cell + 1.0) * randomness;
  return min(abs((mid + left) / 2.0 - local), abs((mid + right) / 2.0 - local));
}

float voronoi_n_sphere_radius(float coord, float randomness, int hash_mode)
{
  float cell = floor(coord);
  float local = coord - cell;
  float closest = 0.0;
  float closest_o = 0.0;
  float min_d = VORONOI_FLT_MAX;
  for (int i = -1; i <= 1; i++) {
    float o = float(i);
    float p = voronoi_point1(cell, o, randomness);
    float d = abs(p - local);
    if (d < min_d) {
      min_d = d;
      closest = p;
      closest_o = o;
    }
  }
  min_d = VORONOI_FLT_MAX;
  float closest2 = 0.0;
  for (int i = -1; i <= 1; i++) {
    if (i == 0) {
      continue;
    }
    float o = float(i) + closest_o;
    float p = voronoi_point1(cell, o, randomness);
    float d = abs(closest - p);
    if (d < min_d) {
      min_d = d;
      closest2 = p;
    }
  }
  return abs(closest2 - closest) / 2.0;
}

/* ---- 2D to 4D, one definition (T: float vector, IT: int vector, N: 3^d, N5: 5^d) ---- */

#define VORONOI_ND(T, IT, N, N5) \
  float voronoi_distance(T a, T b, int metric, float exponent) \
  { \
    T d = abs(a - b); \
    if (metric == VORONOI_MANHATTAN) { \
      return voronoi_sum(d); \
    } \
    if (metric == VORONOI_CHEBYCHEV) { \
      return voronoi_max(d); \
    } \
    if (metric == VORONOI_MINKOWSKI) { \
      return pow(voronoi_sum(pow(d, T(exponent))), 1.0 / exponent); \
    } \
    return distance(a, b); \
  } \
  VoronoiOctave voronoi_f1(T coord, int metric, float exponent, float randomness, int hash_mode) \
  { \
    T cell_f = floor(coord); \
    T local = coord - cell_f; \
    IT cell_i = voronoi_cell_int(cell_f); \
    float min_d = VORONOI_FLT_MAX; \
    IT target_o = IT(0); \
    T target_p = T(0.0); \
    for (int n = 0; n < N; n++) { \
      IT o = voronoi_offset(n, 1, IT(0)); \
      T p = T(o) + voronoi_jitter(cell_f, cell_i, o, hash_mode) * randomness; \
      float d = voronoi_distance(p, local, metric, exponent); \
      if (d < min_d) { \
        target_o = o; \
        min_d = d; \
        target_p = p; \
      } \
    } \
    return VoronoiOctave( \
        min_d, voronoi_color(cell_f, cell_i, target_o, hash_mode), voronoi_position(target_p + cell_f)); \
  } \
  VoronoiOctave voronoi_smooth_f1( \
      T coord, int metric, float exponent, float randomness, float smoothness, int hash_mode) \
  { \
    T cell_f = floor(coord); \
    T local = coord - cell_f; \
    IT cell_i = voronoi_cell_int(cell_f); \
    float smooth_d = 0.0; \
    vec3 smooth_c = vec3(0.0); \
    T smooth_p = T(0.0); \
    float h = -1.0; \
    for (int n = 0; n < N5; n++) { \
      IT o = voronoi_offset(n, 2, IT(0)); \
      T p = T(o) + voronoi_jitter(cell_f, cell_i, o, hash_mode) * randomness; \
      float d = voronoi_distance(p, local, metric, exponent); \
      h = (h == -1.0) ? 1.0 : smoothstep(0.0, 1.0, 0.5 + 0.5 * (smooth_d - d) / smoothness); \
      float correction = smoothness * h * (1.0 - h); \
      smooth_d = mix(smooth_d, d, h) - correction; \
      correction /= 1.0 + 3.0 * smoothness; \
      smooth_c = mix(smooth_c, voronoi_color(cell_f, cell_i, o, hash_mode), h) - correction; \
      smooth_p = mix(smooth_p, p, h) - correction; \
    } \
    return VoronoiOctave(smooth_d, smooth_c, voronoi_position(cell_f + smooth_p)); \
  } \
  VoronoiOctave voronoi_f2(T coord, int metric, float exponent, float randomness, int hash_mode) \
  { \
    T cell_f = floor(coord); \
    T local = coord - cell_f; \
    IT cell_i = voronoi_cell_int(cell_f); \
    float d1 = VORONOI_FLT_MAX; \
    float d2 = VORONOI_FLT_MAX; \
    IT o1 = IT(0); \
    IT o2 = IT(0); \
    T p1 = T(0.0); \
    T p2 = T(0.0); \
    for (int n = 0; n < N; n++) { \
      IT o = voronoi_offset(n, 1, IT(0)); \
      T p = T(o) + voronoi_jitter(cell_f, cell_i, o, hash_mode) * randomness; \
      float d = voronoi_distance(p, local, metric, exponent); \
      if (d < d1) { \
        d2 = d1; \
        d1 = d; \
        o2 = o1; \
        o1 = o; \
        p2 = p1; \
        p1 = p; \
      } \
      else if (d < d2) { \
        d2 = d; \
        o2 = o; \
        p2 = p; \
      } \
    } \
    return VoronoiOctave(d2, voronoi_color(cell_f, cell_i, o2, hash_mode), voronoi_position(p2 + cell_f)); \
  } \
  float voronoi_distance_to_edge(T coord, float randomness, int hash_mode) \
  { \
    T cell_f = floor(coord); \
    T local = coord - cell_f; \
    IT cell_i = voronoi_cell_int(cell_f); \
    T to_closest = T(0.0); \
    float min_d = VORONOI_FLT_MAX; \
    for (int n = 0; n < N; n++) { \
      IT o = voronoi_offset(n, 1, IT(0)); \
      T v = T(o) + voronoi_jitter(cell_f, cell_i, o, hash_mode) * randomness - local; \
      float d = dot(v, v); \
      if (d < min_d) { \
        min_d = d; \
        to_closest = v; \
      } \
    } \
    min_d = VORONOI_FLT_MAX; \
    for (int n = 0; n < N; n++) { \
      IT o = voronoi_offset(n, 1, IT(0)); \
      T v = T(o) + voronoi_jitter(cell_f, cell_i, o, hash_mode) * randomness - local; \
      T perpendicular = v - to_closest; \
      if (dot(perpendicular, perpendicular) > 0.0001) { \
        min_d = min(min_d, dot((to_closest + v) / 2.0, normalize(perpendicular))); \
      } \
    } \
    return min_d; \
  } \
  float voronoi_n_sphere_radius(T coord, float randomness, int hash_mode) \
  { \
    T cell_f = floor(coord); \
    T local = coord - cell_f; \
    IT cell_i = voronoi_cell_int(cell_f); \
    T closest = T(0.0); \
    IT closest_o = IT(0); \
    float min_d = VORONOI_FLT_MAX; \
    for (int n = 0; n < N; n++) { \
      IT o = voronoi_offset(n, 1, IT(0)); \
      T p = T(o) + voronoi_jitter(cell_f, cell_i, o, hash_mode) * randomness; \
      float d = distance(p, local); \
      if (d < min_d) { \
        min_d = d; \
        closest = p; \
        closest_o = o; \
      } \
    } \
    min_d = VORONOI_FLT_MAX; \
    T closest2 = T(0.0); \
    for (int n = 0; n < N; n++) { \
      IT o = voronoi_offset(n, 1, IT(0)); \
      if (o == IT(0)) { \
        continue; \
      } \
      o += closest_o; \
      T p = T(o) + voronoi_jitter(cell_f, cell_i, o, hash_mode) * randomness; \
      float d = distance(closest, p); \
      if (d < min_d) { \
        min_d = d; \
        closest2 = p; \
      } \
    } \
    return distance(closest2, closest) / 2.0; \
  }
VORONOI_ND(vec2, ivec2, 9, 25)
VORONOI_ND(vec3, ivec3, 27, 125)
VORONOI_ND(vec4, ivec4, 81, 625)

/* ---- Fractal octaves, every dimension ---- */

#define VORONOI_FRACTAL(T) \
  VoronoiOctave voronoi_fractal(T coord, \
                                int feature, \
                                int metric, \
                                float exponent, \
                                float randomness, \
                                float smoothness, \
                                float detail, \
                                float roughness, \
                                float lacunarity, \
                                bool normalize, \
                                float max_distance, \
                                float scale, \
                                int hash_mode) \
  { \
    float amplitude = 1.0; \
    float max_amplitude = 0.0; \
    float octave_scale = 1.0; \
    VoronoiOctave result = VoronoiOctave(0.0, vec3(0.0), vec4(0.0)); \
    bool zero_input = detail == 0.0 || roughness == 0.0; \
    for (int i = 0; i <= NODE_MAX_OCTAVE && i <= int(ceil(detail)); i++) { \
      T c = texture_finite(coord * octave_scale); \
      VoronoiOctave octave; \
      if (feature == VORONOI_F2) { \
        octave = voronoi_f2(c, metric, exponent, randomness, hash_mode); \
      } \
      else if (feature == VORONOI_SMOOTH_F1 && smoothness != 0.0) { \
        octave = voronoi_smooth_f1(c, metric, exponent, randomness, smoothness, hash_mode); \
      } \
      else { \
        octave = voronoi_f1(c, metric, exponent, randomness, hash_mode); \
      } \
      if (zero_input) { \
        max_amplitude = 1.0; \
        result = octave; \
        break; \
      } \
      if (float(i) <= detail) { \
        max_amplitude += amplitude; \
        result.distance += octave.distance * amplitude; \
        result.color += octave.color * amplitude; \
        result.position = mix(result.position, octave.position / octave_scale, amplitude); \
        octave_scale *= lacunarity; \
        amplitude *= roughness; \
      } \
      else { \
        float remainder = detail - floor(detail); \
        if (remainder != 0.0) { \
          max_amplitude = mix(max_amplitude, max_amplitude + amplitude, remainder); \
          result.distance = mix(result.distance, result.distance + octave.distance * amplitude, remainder); \
          result.color = mix(result.color, result.color + octave.color * amplitude, remainder); \
          result.position = mix( \
              result.position, mix(result.position, octave.position / octave_scale, amplitude), remainder); \
        } \
      } \
    } \
    if (normalize) { \
      result.distance /= max_amplitude * max_distance; \
      result.color /= max_amplitude; \
    } \
    result.position = (scale != 0.0) ? result.position / scale : vec4(0.0); \
    return result; \
  } \
  float voronoi_fractal_edge(T coord, \
                             float randomness, \
                             float detail, \
                             float roughness, \
                             float lacunarity, \
                             bool normalize, \
                             float max_distance, \
                             int hash_mode) \
  { \
    float amplitude = 1.0; \
    float max_amplitude = max_distance; \
    float octave_scale = 1.0; \
    float dist = 8.0; \
    bool zero_input = detail == 0.0 || roughness == 0.0; \
    for (int i = 0; i <= NODE_MAX_OCTAVE && i <= int(ceil(detail)); i++) { \
      float octave_d = voronoi_distance_to_edge(texture_finite(coord * octave_scale), randomness, hash_mode); \
      if (zero_input) { \
        dist = octave_d; \
        break; \
      } \
      if (float(i) <= detail) { \
        max_amplitude = mix(max_amplitude, max_distance / octave_scale, amplitude); \
        dist = mix(dist, min(dist, octave_d / octave_scale), amplitude); \
        octave_scale *= lacunarity; \
        amplitude *= roughness; \
      } \
      else { \
        float remainder = detail - floor(detail); \
        if (remainder != 0.0) { \
          float lerp_amplitude = mix(max_amplitude, max_distance / octave_scale, amplitude); \
          max_amplitude = mix(max_amplitude, lerp_amplitude, remainder); \
          float lerp_d = mix(dist, min(dist, octave_d / octave_scale), amplitude); \
          dist = mix(dist, min(dist, lerp_d), remainder); \
        } \
      } \
    } \
    if (normalize) { \
      dist /= max_amplitude; \
    } \
    return dist; \
  }
VORONOI_FRACTAL(float)
VORONOI_FRACTAL(vec2)
VORONOI_FRACTAL(vec3)
VORONOI_FRACTAL(vec4)

/* The Voronoi Texture node for one dimension, on the scaled coordinate p (1D: w; 2D: vector.xy;
 * 3D: vector; 4D: (vector, w)); `scale` only divides the Position output back. Outputs as
 * Blender's node: Distance, Color, Position (xyz) and W in .w, Radius (the outputs a feature
 * does not produce are 0). */
#define VORONOI_NODE(T) \
  void node_tex_voronoi_at(T p, \
                           int feature, \
                           int metric, \
                           float scale, \
                           float detail, \
                           float roughness, \
                           float lacunarity, \
                           float smoothness, \
                           float exponent, \
                           float randomness, \
                           bool normalize, \
                           int hash_mode, \
                           out float out_distance, \
                           out vec3 out_color, \
                           out vec4 out_position, \
                           out float out_radius) \
  { \
    detail = node_detail(detail); \
    roughness = clamp(roughness, 0.0, 1.0); \
    randomness = clamp(randomness, 0.0, 1.0); \
    smoothness = clamp(smoothness / 2.0, 0.0, 0.5); \
    out_distance = 0.0; \
    out_color = vec3(0.0); \
    out_position = vec4(0.0); \
    out_radius = 0.0; \
    float half_cell = 0.5 + 0.5 * randomness; \
    if (feature == VORONOI_DISTANCE_TO_EDGE) { \
      out_distance = voronoi_fractal_edge( \
          p, randomness, detail, roughness, lacunarity, normalize, half_cell, hash_mode); \
    } \
    else if (feature == VORONOI_N_SPHERE_RADIUS) { \
      out_radius = voronoi_n_sphere_radius(p, randomness, hash_mode); \
    } \
    else { \
      float max_distance = voronoi_distance(T(0.0), T(half_cell), metric, exponent) * \
                           ((feature == VORONOI_F2) ? 2.0 : 1.0); \
      VoronoiOctave result = voronoi_fractal(p, feature, metric, exponent, randomness, smoothness, \
                                             detail, roughness, lacunarity, normalize, \
                                             max_distance, scale, hash_mode); \
      out_distance = result.distance; \
      out_color = result.color; \
      out_position = result.position; \
    } \
  }
VORONOI_NODE(float)
VORONOI_NODE(vec2)
VORONOI_NODE(vec3)
VORONOI_NODE(vec4)

/* The node's inputs as Blender takes them: Vector, W and Scale; non-finite inputs read as 0.
 * Calls one dimension only; generated code that knows the dimension calls node_tex_voronoi_at. */
void node_tex_voronoi(int dimensions,
                      int feature,
                      int metric,
                      vec3 vector,
                      float w,
                      float scale,
                      float detail,
                      float roughness,
                      float lacunarity,
                      float smoothness,
                      float exponent,
                      float randomness,
                      bool normalize,
                      int hash_mode,
                      out float out_distance,
                      out vec3 out_color,
                      out vec4 out_position,
                      out float out_radius)
{
  vector = texture_finite(texture_finite(vector) * scale);
  w = texture_finite(texture_finite(w) * scale);
  if (dimensions == 1) {
    node_tex_voronoi_at(w, feature, metric, scale, detail, roughness, lacunarity, smoothness, exponent,
                        randomness, normalize, hash_mode, out_distance, out_color, out_position, out_radius);
  }
  else if (dimensions == 2) {
    node_tex_voronoi_at(vector.xy, feature, metric, scale, detail, roughness, lacunarity, smoothness, exponent,
                        randomness, normalize, hash_mode, out_distance, out_color, out_position, out_radius);
  }
  else if (dimensions == 3) {
    node_tex_voronoi_at(vector, feature, metric, scale, detail, roughness, lacunarity, smoothness, exponent,
                        randomness, normalize, hash_mode, out_distance, out_color, out_position, out_radius);
  }
  else {
    node_tex_voronoi_at(vec4(vector, w), feature, metric, scale, detail, roughness, lacunarity, smoothness,
                        exponent, randomness, normalize, hash_mode, out_distance, out_color, out_position,
                        out_radius);
  }
}

#endif /* PENUMBRA_LIB_NODES_TEXTURE_VORONOI */
