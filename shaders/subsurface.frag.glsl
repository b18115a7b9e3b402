/* The subsurface diffusion of one sample (engine/frame/features/subsurface.py), added to the
 * sample's colour: at each subsurface pixel, the light entering the surface around it (the
 * subsurface draw's light over its albedo, lib/subsurface.glsl) spread over Burley's profile
 * (lib/burley.glsl) and multiplied by the albedo here (Golubev 2018, "Efficient Screen-Space
 * Subsurface Scattering Using Burley's Normalized Diffusion in Real-Time"; EEVEE's approach).
 *
 * ``taps`` points a pixel and sample, drawn anew each sample (the R2 sequence over the frame's
 * taps, rotated per pixel): a channel in turn, a radius from its profile, an angle; the point
 * is taken on the plane facing the camera at this pixel's depth and its own depth read back.
 * Each channel weighs a point by its profile at their distance (the radius across the view and
 * the depth between them) over the density it was drawn with (the channels' mean, as Cycles'
 * disk sampling), and the weights are normalised
 * over the points that are subsurface pixels (the rest of the disk leaves the screen or the
 * surface): what lies outside is not counted as dark. */

/* Pixels per world unit across the view at view depth ``z``. */
float pixels_per_unit(float z)
{
  float scale = 0.5 * viewport_size.x * projection[0][0];
  return (is_ortho > 0.5) ? scale : scale / max(z, 1e-20);
}

#define ALBEDO_MIN 1e-6

void main()
{
  ivec2 p = ivec2(gl_FragCoord.xy);
  vec4 radius = texelFetch(sss_radius, p, 0);
  vec4 centre = texelFetch(sss_albedo, p, 0);
  if (radius.a <= 0.0 || max(max(centre.r, centre.g), centre.b) <= 0.0) {
    discard; /* no subsurface share here */
  }
  vec3 light = texelFetch(sss_light, p, 0).rgb;
  vec3 d = radius.rgb;
  vec3 A = centre.rgb;
  /* (An albedo below ALBEDO_MIN in a channel holds no light to divide out there.) */
  vec3 entering = vec3(A.r > ALBEDO_MIN ? light.r / A.r : 0.0, A.g > ALBEDO_MIN ? light.g / A.g : 0.0,
                       A.b > ALBEDO_MIN ? light.b / A.b : 0.0);
  float z = centre.a;
  float per_unit = pixels_per_unit(z);
  /* A profile within the pixel: the light stays where it entered. */
  float reach = BURLEY_TRUNCATE * max(max(d.r, d.g), d.b) * per_unit;
  if (reach < 0.5 || !(z > 0.0)) {
    out_color = vec4(light, 0.0);
    return;
  }
  bvec3 live = greaterThan(d, vec3(0.0));
  int channels = int(live.r) + int(live.g) + int(live.b);
  /* The R2 sequence over the frame's taps, rotated per pixel (lib/material.glsl pixel_r2's). */
  vec2 shift = vec2(pixel_hash(gl_FragCoord.xy + 7.0), pixel_hash(gl_FragCoord.xy + 108.0));
  vec3 sum = vec3(0.0), weights = vec3(0.0);
  for (int i = 0; i < taps; i++) {
    vec2 u = fract(shift + float(sample_index * taps + i) * vec2(0.7548776662, 0.5698402910));
    /* The channel in turn among those with a distance. */
    int k = i % channels;
    int ch = live.r ? 0 : (live.g ? 1 : 2);
    for (int c = 0, seen = 0; c < 3; c++) {
      if (live[c]) {
        if (seen == k) {
          ch = c;
        }
        seen++;
      }
    }
    float r = burley_sample(d[ch], u.x);
    if (!(r > 0.0)) {
      continue;
    }
    float phi = 6.283185307179586 * u.y;
    vec2 q = gl_FragCoord.xy + r * per_unit * vec2(cos(phi), sin(phi));
    if (any(lessThan(q, vec2(0.0))) || any(greaterThanEqual(q, viewport_size))) {
      continue;
    }
    ivec2 qi = ivec2(q);
    vec4 there_radius = texelFetch(sss_radius, qi, 0);
    vec4 there = texelFetch(sss_albedo, qi, 0);
    if (there_radius.a <= 0.0 || !(there.a > 0.0)) {
      continue;
    }
    vec3 there_light = texelFetch(sss_light, qi, 0).rgb;
    /* Its distance: the drawn radius across the view (not the pixel centre's, which would
     * make the profile's 1 / r peak of the nearest pixels) and the depth between them. */
    float dz = there.a - z;
    float dist = sqrt(r * r + dz * dz);
    /* The density the point was drawn with: the channels' mean of the radial density over the
     * circle's length 2 pi r (the profile R itself is the radial density over 2 pi dist). */
    float density = 0.0;
    for (int c = 0; c < 3; c++) {
      density += live[c] ? burley_radial(d[c], r) : 0.0;
    }
    density /= float(channels) * r;
    if (!(density > 0.0)) {
      continue;
    }
    for (int c = 0; c < 3; c++) {
      if (live[c] && there[c] > ALBEDO_MIN) {
        float w = burley_radial(d[c], dist) / (dist * density);
        weights[c] += w;
        sum[c] += w * there_light[c] / there[c];
      }
    }
  }
  vec3 spread;
  for (int c = 0; c < 3; c++) {
    spread[c] = (live[c] && weights[c] > 0.0) ? sum[c] / weights[c] : entering[c];
  }
  out_color = vec4(max(A * spread, vec3(0.0)), 0.0);
}
