/* Radial bulge/pinch; the mapping is fisheye.py's fisheye_source. edge_mode is one of the
 * EDGE_* values generated from fisheye.py's EDGE enum. */

/* Texel index i of an axis of n texels, folded back into the image (clamp or mirrored repeat). */
int edge_index(int i, int n)
{
  if (edge_mode == EDGE_MIRROR) {
    int period = 2 * n;
    int m = i - period * int(floor(float(i) / float(period)));
    return (m >= n) ? period - 1 - m : m;
  }
  return clamp(i, 0, n - 1);
}

vec4 tap(ivec2 i, ivec2 size)
{
  if (edge_mode == EDGE_BLACK && (any(lessThan(i, ivec2(0))) || any(greaterThanEqual(i, size)))) {
    return vec4(0.0);
  }
  ivec2 q = ivec2(edge_index(i.x, size.x), edge_index(i.y, size.y));
  return sanitize(texelFetch(source_tex, q, 0));
}

/* Bilinear read at position p in pixels (texel centres at i + 0.5), by hand so the edge modes
 * and the weights are exact and independent of the texture's sampler state. */
vec4 sample_bilinear(vec2 p)
{
  ivec2 size = textureSize(source_tex, 0);
  vec2 t = p - 0.5;
  vec2 t0 = floor(t);
  vec2 f = t - t0;
  ivec2 i0 = ivec2(t0);
  vec4 c00 = tap(i0, size);
  vec4 c10 = tap(i0 + ivec2(1, 0), size);
  vec4 c01 = tap(i0 + ivec2(0, 1), size);
  vec4 c11 = tap(i0 + ivec2(1, 1), size);
  return mix(mix(c00, c10, f.x), mix(c01, c11, f.x), f.y);
}

void main()
{
  vec2 centre = 0.5 * target_size;
  vec2 d = gl_FragCoord.xy - centre;
  float r = length(d) / length(centre);
  float k = exp2(strength);
  /* Source radius r^k along the same ray: scale d by r^(k-1) (1 at the centre itself). */
  vec2 source = centre + ((r > 0.0) ? d * pow(r, k - 1.0) : d);
  out_color = post_mix(sample_bilinear(source));
}
