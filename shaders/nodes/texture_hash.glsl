// requires:
#ifndef PENUMBRA_LIB_NODES_TEXTURE_HASH
#define PENUMBRA_LIB_NODES_TEXTURE_HASH

/* Hashes of Blender's procedural textures, bit for bit.
 *
 * - Bob Jenkins' lookup3 (http://burtleburtle.net/bob/c/lookup3.c, "final" and "mix"), seeded
 *   as Blender seeds it (0xdeadbeef + (length << 2) + 13) for 1 to 4 32-bit words: Blender's
 *   hash_uint .. hash_uint4. Floats are hashed by their bit pattern (floatBitsToUint), and a
 *   hash becomes a float in [0, 1] as hash / 2^32 (Blender's hash_*_to_float).
 * - The PCG 2D/3D/4D hashes of Jarzynski and Olano, "Hash Functions for GPU Rendering", JCGT 9(3)
 *   2020, in Blender's signed-integer variant (arithmetic right shift, result masked to 31 bits):
 *   the Voronoi texture hashes its integer cell coordinates with them (hash_int*_to_vec*).
 *
 * uint arithmetic wraps modulo 2^32 in GLSL, as lookup3 expects. */

uint hash_rotl(uint x, uint k)
{
  return (x << k) | (x >> (32u - k));
}

/* lookup3's "final": mixes the three state words into c. */
uint hash_final(uint a, uint b, uint c)
{
  c ^= b;
  c -= hash_rotl(b, 14u);
  a ^= c;
  a -= hash_rotl(c, 11u);
  b ^= a;
  b -= hash_rotl(a, 25u);
  c ^= b;
  c -= hash_rotl(b, 16u);
  a ^= c;
  a -= hash_rotl(c, 4u);
  b ^= a;
  b -= hash_rotl(a, 14u);
  c ^= b;
  c -= hash_rotl(b, 24u);
  return c;
}

uint hash_uint(uint kx)
{
  uint s = 0xdeadbeefu + (1u << 2u) + 13u;
  return hash_final(s + kx, s, s);
}

uint hash_uint2(uint kx, uint ky)
{
  uint s = 0xdeadbeefu + (2u << 2u) + 13u;
  return hash_final(s + kx, s + ky, s);
}

uint hash_uint3(uint kx, uint ky, uint kz)
{
  uint s = 0xdeadbeefu + (3u << 2u) + 13u;
  return hash_final(s + kx, s + ky, s + kz);
}

uint hash_uint4(uint kx, uint ky, uint kz, uint kw)
{
  uint s = 0xdeadbeefu + (4u << 2u) + 13u;
  uint a = s + kx;
  uint b = s + ky;
  uint c = s + kz;
  /* lookup3's "mix" of the first three words, then the fourth goes through "final". */
  a -= c;
  a ^= hash_rotl(c, 4u);
  c += b;
  b -= a;
  b ^= hash_rotl(a, 6u);
  a += c;
  c -= b;
  c ^= hash_rotl(b, 8u);
  b += a;
  a -= c;
  a ^= hash_rotl(c, 16u);
  c += b;
  b -= a;
  b ^= hash_rotl(a, 19u);
  a += c;
  c -= b;
  c ^= hash_rotl(b, 4u);
  b += a;
  return hash_final(a + kw, b, c);
}

uint hash_int(int kx)
{
  return hash_uint(uint(kx));
}

uint hash_int2(int kx, int ky)
{
  return hash_uint2(uint(kx), uint(ky));
}

uint hash_int3(int kx, int ky, int kz)
{
  return hash_uint3(uint(kx), uint(ky), uint(kz));
}

uint hash_int4(int kx, int ky, int kz, int kw)
{
  return hash_uint4(uint(kx), uint(ky), uint(kz), uint(kw));
}

/* A 32-bit hash as a float in [0, 1]: the nearest float to h, times 2^-32. */
float hash_uint_to_unit(uint h)
{
  return float(h) * (1.0 / 4294967296.0);
}

float hash_uint_to_float(uint kx)
{
  return hash_uint_to_unit(hash_uint(kx));
}

float hash_uint2_to_float(uint kx, uint ky)
{
  return hash_uint_to_unit(hash_uint2(kx, ky));
}

float hash_uint3_to_float(uint kx, uint ky, uint kz)
{
  return hash_uint_to_unit(hash_uint3(kx, ky, kz));
}

float hash_uint4_to_float(uint kx, uint ky, uint kz, uint kw)
{
  return hash_uint_to_unit(hash_uint4(kx, ky, kz, kw));
}

float hash_float_to_float(float k)
{
  return hash_uint_to_float(floatBitsToUint(k));
}

float hash_vec2_to_float(vec2 k)
{
  return hash_uint2_to_float(floatBitsToUint(k.x), floatBitsToUint(k.y));
}

float hash_vec3_to_float(vec3 k)
{
  return hash_uint3_to_float(floatBitsToUint(k.x), floatBitsToUint(k.y), floatBitsToUint(k.z));
}

float hash_vec4_to_float(vec4 k)
{
  uvec4 u = floatBitsToUint(k);
  return hash_uint4_to_float(u.x, u.y, u.z, u.w);
}

/* Vector-valued float hashes: Blender's component orders and appended constants. */
vec2 hash_float_to_vec2(float k)
{
  return vec2(hash_float_to_float(k), hash_vec2_to_float(vec2(k, 1.0)));
}

vec3 hash_float_to_vec3(float k)
{
  return vec3(hash_float_to_float(k), hash_vec2_to_float(vec2(k, 1.0)), hash_vec2_to_float(vec2(k, 2.0)));
}

vec2 hash_vec2_to_vec2(vec2 k)
{
  return vec2(hash_vec2_to_float(k), hash_vec3_to_float(vec3(k, 1.0)));
}

vec3 hash_vec2_to_vec3(vec2 k)
{
  return vec3(hash_vec2_to_float(k), hash_vec3_to_float(vec3(k, 1.0)), hash_vec3_to_float(vec3(k, 2.0)));
}

vec2 hash_vec3_to_vec2(vec3 k)
{
  return vec2(hash_vec3_to_float(k), hash_vec3_to_float(k.zxy));
}

vec3 hash_vec3_to_vec3(vec3 k)
{
  return vec3(hash_vec3_to_float(k), hash_vec4_to_float(vec4(k, 1.0)), hash_vec4_to_float(vec4(k, 2.0)));
}

vec2 hash_vec4_to_vec2(vec4 k)
{
  return vec2(hash_vec4_to_float(k), hash_vec4_to_float(k.zxwy));
}

vec3 hash_vec4_to_vec3(vec4 k)
{
  return vec3(hash_vec4_to_float(k), hash_vec4_to_float(k.zxwy), hash_vec4_to_float(k.wzyx));
}

vec4 hash_vec4_to_vec4(vec4 k)
{
  return vec4(hash_vec4_to_float(k), hash_vec4_to_float(k.wxyz), hash_vec4_to_float(k.zwxy), hash_vec4_to_float(k.yzwx));
}

/* PCG hashes of integer vectors (signed, wrapping multiply; >> is arithmetic on int). */
ivec2 hash_pcg2d_i(ivec2 v)
{
  v = v * 1664525 + 1013904223;
  v.x += v.y * 1664525;
  v.y += v.x * 1664525;
  v = v ^ (v >> 16);
  v.x += v.y * 1664525;
  v.y += v.x * 1664525;
  return v & 0x7fffffff;
}

ivec3 hash_pcg3d_i(ivec3 v)
{
  v = v * 1664525 + 1013904223;
  v.x += v.y * v.z;
  v.y += v.z * v.x;
  v.z += v.x * v.y;
  v = v ^ (v >> 16);
  v.x += v.y * v.z;
  v.y += v.z * v.x;
  v.z += v.x * v.y;
  return v & 0x7fffffff;
}

ivec4 hash_pcg4d_i(ivec4 v)
{
  v = v * 1664525 + 1013904223;
  v.x += v.y * v.w;
  v.y += v.z * v.x;
  v.z += v.x * v.y;
  v.w += v.y * v.z;
  v = v ^ (v >> 16);
  v.x += v.y * v.w;
  v.y += v.z * v.x;
  v.z += v.x * v.y;
  v.w += v.y * v.z;
  return v & 0x7fffffff;
}

/* 31-bit hashes to [0, 1]: the nearest float to h, times 2^-31. */
vec2 hash_ivec2_to_vec2(ivec2 k)
{
  return vec2(hash_pcg2d_i(k)) * (1.0 / 2147483648.0);
}

vec3 hash_ivec3_to_vec3(ivec3 k)
{
  return vec3(hash_pcg3d_i(k)) * (1.0 / 2147483648.0);
}

vec4 hash_ivec4_to_vec4(ivec4 k)
{
  return vec4(hash_pcg4d_i(k)) * (1.0 / 2147483648.0);
}

vec3 hash_ivec2_to_vec3(ivec2 k)
{
  return hash_ivec3_to_vec3(ivec3(k, 0));
}

vec3 hash_ivec4_to_vec3(ivec4 k)
{
  return hash_ivec4_to_vec4(k).xyz;
}

/* Finite-ness by the bit pattern (exponent all ones = inf or NaN), immune to compilers that
 * assume NaN never occurs. */
bool texture_is_finite(float x)
{
  return (floatBitsToUint(x) & 0x7f800000u) != 0x7f800000u;
}

/* C's (int)f as x86 converts it: truncation toward zero, INT_MIN when f is out of range. */
int texture_float_to_int(float f)
{
  return (abs(f) < 2147483648.0) ? int(f) : (-2147483647 - 1);
}

/* A coordinate as the textures read it: NaN and +-inf become 0, so every output stays finite. */
float texture_finite(float x)
{
  return texture_is_finite(x) ? x : 0.0;
}

vec2 texture_finite(vec2 v)
{
  return vec2(texture_finite(v.x), texture_finite(v.y));
}

vec3 texture_finite(vec3 v)
{
  return vec3(texture_finite(v.x), texture_finite(v.y), texture_finite(v.z));
}

vec4 texture_finite(vec4 v)
{
  return vec4(texture_finite(v.x), texture_finite(v.y), texture_finite(v.z), texture_finite(v.w));
}

#endif /* PENUMBRA_LIB_NODES_TEXTURE_HASH */
