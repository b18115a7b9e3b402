/* Ghosts and halo from the bright parts of the input, merged into it; lens_flare.py defines the
 * flare and the merge modes exactly.
 * halo_radius and halo_width are in units of the half-diagonal; merge_mode is one of the
 * MERGE_* values generated from lens_flare.py's MERGE enum. */

/* Bright pass of one input texel; black outside the image. */
vec3 bright_texel(ivec2 i, ivec2 size)
{
  if (any(lessThan(i, ivec2(0))) || any(greaterThanEqual(i, size))) {
    return vec3(0.0);
  }
  return max(sanitize(texelFetch(source_tex, i, 0)).rgb - threshold, vec3(0.0));
}

/* Bilinear read of the bright pass at position p in pixels (texel centres at i + 0.5). */
vec3 bright_sample(vec2 p)
{
  ivec2 size = textureSize(source_tex, 0);
  vec2 t = p - 0.5;
  vec2 t0 = floor(t);
  vec2 f = t - t0;
  ivec2 i0 = ivec2(t0);
  vec3 c00 = bright_texel(i0, size);
  vec3 c10 = bright_texel(i0 + ivec2(1, 0), size);
  vec3 c01 = bright_texel(i0 + ivec2(0, 1), size);
  vec3 c11 = bright_texel(i0 + ivec2(1, 1), size);
  return mix(mix(c00, c10, f.x), mix(c01, c11, f.x), f.y);
}

void main()
{
  vec4 c = post_source();
  vec2 centre = 0.5 * target_size;
  float diag = length(centre);
  vec2 u = gl_FragCoord.xy - centre;
  float dist = length(u);
  float r = dist / diag;

  vec3 f = vec3(0.0);
  for (int i = 0; i < ghosts; i++) {
    vec2 q = centre + u * (ghost_spacing * float(i) - 1.0);
    float a = 1.0 - saturate(length(q - centre) / diag);
    f += (a * a * a) * bright_sample(q);
  }
  if (halo_width > 0.0) {
    float t = saturate(1.0 - abs(r - halo_radius) / halo_width);
    float ring = t * t * (3.0 - 2.0 * t);
    if (ring > 0.0) {
      vec2 dir = (dist > 0.0) ? u / dist : vec2(0.0);
      f += ring * bright_sample(centre + dir * (halo_radius * diag - dist));
    }
  }

  vec3 tint;
  if (lens_image != 0) {
    tint = texel_bilinear(lens_tex, gl_FragCoord.xy / target_size * vec2(textureSize(lens_tex, 0)) - 0.5);
  }
  else {
    tint = texel_bilinear(lens_tex, vec2(r * float(textureSize(lens_tex, 0).x - 1), 0.0));
  }
  f *= intensity * tint;

  vec3 merged;
  if (merge_mode == MERGE_SCREEN) {
    merged = 1.0 - (1.0 - max(c.rgb, 0.0)) * (1.0 - max(f, 0.0));
  }
  else if (merge_mode == MERGE_AVERAGE) {
    merged = 0.5 * (c.rgb + f);
  }
  else if (merge_mode == MERGE_DIFFERENCE) {
    merged = abs(c.rgb - f);
  }
  else {
    merged = c.rgb + f;
  }
  out_color = post_mix(vec4(merged, c.a));
}
