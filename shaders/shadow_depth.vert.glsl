/* Light-space depth pass. The tile's proj_tex maps to texture space; clip space is recovered
 * from it (tex.xyz = 0.5 * clip.xyz + 0.5 * clip.w), so one tile record serves both passes. */
void main()
{
  vec4 view_pos = tile.view * (model * vec4(pos, 1.0));
  v_distance = -view_pos.z;
#if HAS_UV
  v_uv = uv;
#endif
#if NODE_TREE
  /* A compiled node tree gives this caster's alpha: the surface data it reads. */
  vec4 wp = model * vec4(pos, 1.0);
  mat3 m = mat3(model);
  mat3 cof = mat3(cross(m[1], m[2]), cross(m[2], m[0]), cross(m[0], m[1]));
  v_world = wp.xyz;
  v_normal = cof * nor * (dot(m[0], cof[0]) < 0.0 ? -1.0 : 1.0);
#  if HAS_VCOL
  v_color = col;
#  endif
#endif
  vec4 t = tile.proj_tex * view_pos;
  gl_Position = vec4(2.0 * t.xyz - t.w, t.w);
  /* Pancaking: a caster nearer the light than the tile's near plane is flattened onto it
   * (depth 0) instead of clipped away, so it still occludes what is behind it; the tile's
   * depth range then only has to span the receivers. (x, y do not depend on z.) */
  if (gl_Position.w > 0.0) {
    gl_Position.z = max(gl_Position.z, -gl_Position.w);
  }
}
