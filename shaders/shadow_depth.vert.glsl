/* Light-space depth pass. The tile's proj_tex maps to texture space; clip space is recovered
 * from it (tex.xyz = 0.5 * clip.xyz + 0.5 * clip.w), so one tile record serves both passes.
 * CAMERA_DEPTH: the camera depth prepass of the world's ambient occlusion (engine/frame/
 * world/occlusion.py), whose tile is the lit pass's raster camera. */
void main()
{
#if INSTANCED
  /* One draw fills this caster's maps of the sample (shadow_maps.py ShadowAtlas.render):
   * instance i draws into the tile the instance table names (four to an ivec4). */
  int slot = instance_base + gl_InstanceID;
  v_tile = instance_tiles[slot >> 2].tile[slot & 3];
  ShadowTile tile = tiles[v_tile];
#endif
  vec4 view_pos = tile.view * (model * vec4(pos, 1.0));
#if HAIR_STRIP
  {
    /* A hair strip (engine/scene/hair.py) widened across the strand facing the light, as EEVEE
     * draws curves toward the shadow view: by the strand's radius, or one map texel
     * (hair_texels > 0, Strand shape: a pixel-wide strand is a texel wide in the map). */
    mat3 m = mat3(model);
    vec3 tangent = mat3(tile.view) * (m * nor);
    bool ortho = tile.proj_tex[2][3] == 0.0;
    vec3 V = ortho ? vec3(0.0, 0.0, 1.0) : -view_pos.xyz;
    vec3 B = cross(V, tangent);
    float bl = length(B);
    B = (bl > 1e-20) ? B / bl : vec3(1.0, 0.0, 0.0);
    float half_width = hair.y * pow(abs(determinant(m)), 1.0 / 3.0);
    if (hair_texels > 0.0) {
      half_width = 0.5 * (ortho ? tile.texel : tile.texel_per_distance * max(-view_pos.z, 0.0));
    }
    view_pos.xyz += B * (hair.x * half_width);
  }
#endif
  v_distance = -view_pos.z;
#if RSM_OUTPUT
  {
    /* Reflective shadow maps: the world normal (the model's cofactor, as mesh.vert) and the
     * direction towards the light, turned to world space (the view is rigid). */
    mat3 mr = mat3(model);
    mat3 cr = mat3(cross(mr[1], mr[2]), cross(mr[2], mr[0]), cross(mr[0], mr[1]));
    v_rsm_normal = cr * nor * (dot(mr[0], cr[0]) < 0.0 ? -1.0 : 1.0);
    vec3 toward = (tile.proj_tex[2][3] == 0.0) ? vec3(0.0, 0.0, 1.0) : -view_pos.xyz;
    v_rsm_to_light = transpose(mat3(tile.view)) * toward;
  }
#endif
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
#if INSTANCED
  /* The tile's texture square [0, 1]^2 (homogeneous: 0 <= t.xy <= t.w) onto its place in the
   * atlas, whose whole extent is the viewport, and nothing drawn outside it. */
  gl_Position.xy = 2.0 * (vec2(tile.origin) * t.w + t.xy * float(tile.size)) / atlas_size - t.w;
  gl_ClipDistance[0] = t.x;
  gl_ClipDistance[1] = t.w - t.x;
  gl_ClipDistance[2] = t.y;
  gl_ClipDistance[3] = t.w - t.y;
#endif
#if !CAMERA_DEPTH && RASTER_DEPTH
  /* Pancaking: a caster nearer the light than the tile's near plane is flattened onto it
   * (depth 0) instead of clipped away, so it still occludes what is behind it; the tile's
   * depth range then only has to span the receivers. (x, y do not depend on z.) Per vertex
   * this is exact only for triangles wholly nearer: a tile with a caster that crosses the
   * plane takes the variant below (shadow_maps.py _crosses_near). The camera depth prepass
   * clips at the near plane, as the lit pass it serves does. */
  if (gl_Position.w > 0.0) {
    gl_Position.z = max(gl_Position.z, -gl_Position.w);
  }
#elif !CAMERA_DEPTH
  /* The fragment writes its own depth, clamped to the tile's range (shadow_depth.frag): exact
   * pancaking before the near plane, and nothing clipped in depth at all, for clipping
   * against a plane computes where triangles end from the vertices' depths, and a caster
   * that crosses the near plane would have lost the part of it the far plane cut at the
   * wrong place (a ground under light from below it, missing beneath the boxes on it).
   * Behind a perspective light (w < 0) triangles are still clipped. */
  gl_Position.z = 0.0;
#endif
}
