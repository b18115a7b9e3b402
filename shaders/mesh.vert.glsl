/* World-space position and normal for the lit pass. The normal matrix is the cofactor of the
 * model matrix (det * inverse-transpose): defined for zero scale, and its sign flip keeps
 * normals outward under negative scale. Tangents (normal maps) move with the model matrix;
 * their bitangent sign flips with a mirroring one. With TERMINATOR_OFFSET the triangle's corner
 * data (engine/scene/terminator.py corner_data) passes through, and the object normal moves by
 * the model matrix itself (Cycles' direction transform of the offset's normal).
 * HAIR_STRIP: a hair strip's vertex (engine/scene/hair.py) on the strand, ``nor`` its tangent,
 * moved sideways across the tangent facing the camera by the strand's radius (times the model's
 * scale) or half a pixel (hair_pixel > 0, Strand shape), as EEVEE builds its curve strips; the
 * normal faces the camera and v_hair carries the strip's binormal and side for the fragment
 * stage's cylinder normal. */
void main()
{
  vec4 wp = model * vec4(pos, 1.0);
  mat3 m = mat3(model);
  mat3 cof = mat3(cross(m[1], m[2]), cross(m[2], m[0]), cross(m[0], m[1]));
  float det = dot(m[0], cof[0]);
#if HAIR_STRIP
  {
    vec3 tangent = m * nor;
    float tl = length(tangent);
    tangent = (tl > 1e-20) ? tangent / tl : vec3(0.0, 0.0, 1.0);
    vec3 V = (frame.is_ortho != 0) ? -frame.camera_forward : frame.camera_position - wp.xyz;
    vec3 B = cross(V, tangent);
    float bl = length(B);
    B = (bl > 1e-20) ? B / bl : normalize(cross(abs(tangent.x) < 0.9 ? vec3(1.0, 0.0, 0.0) : vec3(0.0, 1.0, 0.0), tangent));
    float half_width = hair.y * pow(abs(det), 1.0 / 3.0);
    if (hair_pixel > 0.0) {
      half_width = hair_pixel * (frame.view_proj * wp).w;
    }
    wp.xyz += B * (hair.x * half_width);
    v_normal = cross(tangent, B);
    v_hair = vec4(B, hair.x);
  }
#else
  v_normal = cof * nor * (det < 0.0 ? -1.0 : 1.0);
#endif
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
