// requires: nodes/texture_hash.glsl
#ifndef PENUMBRA_LIB_NODES_TEXTURE_WHITE_NOISE
#define PENUMBRA_LIB_NODES_TEXTURE_WHITE_NOISE

/* Blender's White Noise Texture node: the lookup3 hash (texture_hash.glsl) of the coordinate's
 * float bits, 1 to 4 dimensions, as Blender's node_white_noise_1d .. _4d: Value is the hash of
 * the coordinate, Color the vector hash Blender uses for that dimension. No scale: any change of
 * the input's bits gives another value. */

/* dimensions 1..4 (1: w; 2: vector.xy; 3: vector; 4: vector, w). Color in .rgb, Value in .a. */
vec4 node_tex_white_noise(int dimensions, vec3 vector, float w)
{
  if (dimensions == 1) {
    return vec4(hash_float_to_vec3(w), hash_float_to_float(w));
  }
  if (dimensions == 2) {
    return vec4(hash_vec2_to_vec3(vector.xy), hash_vec2_to_float(vector.xy));
  }
  if (dimensions == 3) {
    return vec4(hash_vec3_to_vec3(vector), hash_vec3_to_float(vector));
  }
  vec4 p = vec4(vector, w);
  return vec4(hash_vec4_to_vec3(p), hash_vec4_to_float(p));
}

#endif /* PENUMBRA_LIB_NODES_TEXTURE_WHITE_NOISE */
