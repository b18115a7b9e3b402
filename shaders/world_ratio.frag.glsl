/* The resolve of a frame whose world light is a ratio (features.world_ratio.RESOLVE,
 * lib/world_ratio.glsl): the accumulated colour and SH light by lobe over the pixel's weight
 * (per_pixel > 0.5: its own, else ``scale`` = 1 / the total), shadowed by the ratio of the
 * accumulated sums (which needs no weight: both sums carry the same). */
void main()
{
  ivec2 p = ivec2(gl_FragCoord.xy);
  float inverse = scale;
  if (per_pixel > 0.5) {
    float w = texelFetch(weight, p, 0).r;
    inverse = (w > 0.0) ? 1.0 / w : 0.0;
  }
  vec4 color = texelFetch(src_color, p, 0) * inverse;
  vec3 u_d = texelFetch(world_diffuse, p, 0).rgb * inverse;
  vec3 u_s = texelFetch(world_specular, p, 0).rgb * inverse;
  out_color = world_ratio_apply(color, u_d, u_s, texelFetch(world_sums, p, 0));
}
