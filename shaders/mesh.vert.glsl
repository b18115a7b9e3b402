/* World-space position and normal for the lit pass. The normal matrix is the cofactor of the
 * model matrix (det * inverse-transpose): defined for zero scale, and its sign flip keeps
 * normals outward under negative scale. Tangents (normal maps) move with the model matrix;
 * their bitangent sign flips with a mirroring one. With TERMINATOR_OFFSET the triangle's corner
 * data (engine/scene/terminator.py corner_data) passes through, and the object normal moves by
 * the model matrix itself (Cycles' direction transform of the offset's normal). */
void main()
{
  vec4 wp = model * vec4(pos, 1.0);
  mat3 m = mat3(model);
  mat3 cof = mat3(cross(m[1], m[2]), cross(m[2], m[0]), cross(m[0], m[1]));
  float det = dot(m[0], cof[0]);
  v_normal = cof * nor * (det < 0.0 ? -1.0 : 1.0);
  v_world = wp.xyz;
  v_view_depth = -(frame.view * wp).z;
#if HAS_UV
  v_uv = uv;
#endif
#if HAS_VCOL
  v_color = col;
#endif
#if TERMINATOR_OFFSET
  v_tbary = tbary;
  v_tabc = tabc;
  v_tfront = tfront;
  v_tback = tback;
  v_tnormal = m * nor;
#endif
#if HAS_TANGENT
  v_tangent = vec4(m * tan.xyz, tan.w * (det < 0.0 ? -1.0 : 1.0));
#endif
  gl_Position = frame.view_proj * wp;
}
