// requires: nodes/common.glsl nodes/math.glsl
#ifndef PENUMBRA_LIB_NODES_VECTOR
#define PENUMBRA_LIB_NODES_VECTOR

/* The Vector Math and Mapping nodes (Blender manual: Vector Math, Mapping). ``op`` is a
 * literal (NODE_VECTOR_MATH_* in engine/scene/nodetree.py). Vector Math gives a vector and
 * a value; the operations that give a value (Dot Product, Distance, Length) leave the vector 0,
 * the others leave the value 0. */

vec3 node_vector_wrap(vec3 a, vec3 b, vec3 c)
{
  return vec3(node_math_wrap(a.x, b.x, c.x), node_math_wrap(a.y, b.y, c.y), node_math_wrap(a.z, b.z, c.z));
}

void node_vector_math(const int op, vec3 a, vec3 b, vec3 c, float s, out vec3 v, out float f)
{
  v = vec3(0.0);
  f = 0.0;
  switch (op) {
    case 0: v = a + b; break;
    case 1: v = a - b; break;
    case 2: v = a * b; break;
    case 3: v = node_safe_divide3(a, b); break;
    case 4: v = a * b + c; break;
    case 5: v = cross(a, b); break;
    case 6: {
      float l2 = dot(b, b);
      v = (l2 != 0.0) ? b * (dot(a, b) / l2) : vec3(0.0);
      break;
    }
    case 7: v = reflect(a, node_safe_normalize(b)); break;
    case 8: v = refract(a, node_safe_normalize(b), s); break;
    case 9: v = faceforward(a, b, c); break;
    case 10: f = dot(a, b); break;
    case 11: f = distance(a, b); break;
    case 12: f = length(a); break;
    case 13: v = a * s; break;
    case 14: v = node_safe_normalize(a); break;
    case 15: v = abs(a); break;
    case 16: v = vec3(node_math_power(a.x, b.x), node_math_power(a.y, b.y), node_math_power(a.z, b.z)); break;
    case 17: v = sign(a); break;
    case 18: v = min(a, b); break;
    case 19: v = max(a, b); break;
    case 20: v = floor(a); break;
    case 21: v = ceil(a); break;
    case 22: v = a - floor(a); break;
    case 23: v = vec3(node_math_fmod(a.x, b.x), node_math_fmod(a.y, b.y), node_math_fmod(a.z, b.z)); break;
    case 24: v = node_vector_wrap(a, b, c); break;
    case 25: v = floor(node_safe_divide3(a, b)) * b; break;
    case 26: v = sin(a); break;
    case 27: v = cos(a); break;
    case 28: v = tan(a); break;
  }
}

/* Mapping: 0 Point, 1 Texture (the inverse of Point), 2 Vector (no location), 3 Normal. */
vec3 node_mapping(const int type, vec3 v, vec3 location, vec3 rotation, vec3 scale)
{
  mat3 r = node_euler_to_mat3(rotation);
  switch (type) {
    case 0: return r * (v * scale) + location;
    case 1: return node_safe_divide3(transpose(r) * (v - location), scale);
    case 2: return r * (v * scale);
    case 3: return node_safe_normalize(r * node_safe_divide3(v, scale));
  }
  return v;
}

#endif /* PENUMBRA_LIB_NODES_VECTOR */
