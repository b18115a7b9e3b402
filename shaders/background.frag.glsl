/* The world's Environment Texture behind the scene: the view ray of each pixel (through the
 * inverse view-projection) looked up in the equirectangular image as Blender maps it,
 * u = 0.5 - atan2(y, x) / 2pi, v = atan2(z, hypot(x, y)) / pi + 0.5 (Cycles'
 * direction_to_equirectangular), times the Background
 * strength. */
void main()
{
  vec2 ndc = 2.0 * (gl_FragCoord.xy - viewport_origin) / viewport_size - 1.0;
  vec4 near = inverse_view_proj * vec4(ndc, -1.0, 1.0);
  vec4 far = inverse_view_proj * vec4(ndc, 1.0, 1.0);
  vec3 d = far.xyz / far.w - near.xyz / near.w;
  float len = length(d);
  d = (len > 0.0) ? d / len : vec3(0.0, 0.0, 1.0);
  vec2 uv = vec2(0.5 - atan(d.y, d.x) / (2.0 * M_PI), atan(d.z, length(d.xy)) / M_PI + 0.5);
  /* The footprint from pixel to pixel, across the seam at u = 0 / 1 taken the short way round
   * (else the seam's pixels would read the smallest mip level). */
  vec2 dx = dFdx(uv);
  vec2 dy = dFdy(uv);
  dx.x -= round(dx.x);
  dy.x -= round(dy.x);
  /* A texel's width on the sphere shrinks with cos(latitude): near a pole a quad sweeps much
   * of the image's width but little of the sky, so the longitude footprint is taken at its
   * width on the sphere. (Taken at its width in the image, it chose the image's coarsest
   * mips there, which average the ground half in: grey and dark blotches in the two columns
   * around the zenith of a wide view looking up.) */
  float width = length(d.xy);
  dx.x *= width;
  dy.x *= width;
  vec4 env_color = sample_image_grad(env, uv, dx, dy, ivec4(1, 0, 0, 0), env_premultiplied > 0.5);
  out_color = vec4(strength * env_color.rgb, 1.0);
}
