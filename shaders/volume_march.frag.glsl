/* The media along each pixel's camera ray (engine/frame/features/volumes.py): single
 * scattering of every light through its shadow map, of the world's SH light, and the media's
 * emission, with what they let through of the surface (or background) behind.
 *
 * The ray runs from the camera's clip start (frame.volume_inv_view: the view camera's clip space to world
 * positions relative to the frame origin) to the surface the lit pass left in the z-buffer
 * (frame.volume_inv_raster: the raster camera's), or to the clip end where it met none. The stretch where
 * media lie is cut into ``steps`` equal steps; in each one point is taken with probability
 * proportional to exp(-k (t - a)) (k the mean extinction there), at this sample's own offset
 * (frame.volume_params.w and the pixel's hash), and weighted by exp(-tau(t)) / pdf(t), the
 * optical depth exact (lib/volumes.glsl): the frame's samples average to the integral of
 * T(t) (sigma_s phase L_i + emission) dt, with no banding left.
 *
 * out_transmit: (T, mean T), what is behind is multiplied by; out_scatter: (the light the media
 * add, 1 - mean T), added after (transparent film: the alpha they cover). */

void main()
{
  ivec2 pixel = ivec2(gl_FragCoord.xy);
  vec2 ndc = gl_FragCoord.xy / viewport_size * 2.0 - 1.0;
  float z = texelFetch(scene_depth, pixel, 0).r;
  vec4 a4 = frame.volume_inv_view * vec4(ndc, -1.0, 1.0);
  vec4 b4 = (z < 1.0) ? frame.volume_inv_raster * vec4(ndc, 2.0 * z - 1.0, 1.0) : frame.volume_inv_view * vec4(ndc, 1.0, 1.0);
  vec3 o = a4.xyz / a4.w;
  vec3 p = b4.xyz / b4.w;
  vec3 d = p - o;
  float tmax = length(d);
  if (!(tmax > 0.0) || !is_finite(tmax)) {
    out_transmit = vec4(1.0);
    out_scatter = vec4(0.0);
    return;
  }
  d /= tmax;

  /* Where the media are along the ray, and what they take out of it all. */
  int count = int(frame.volume_params.x);
  float lo = tmax, hi = 0.0;
  vec3 tau_all = vec3(0.0);
  for (int i = 0; i < count; i++) {
    vec2 s = medium_span(media[i], o, d, tmax);
    if (s.y > s.x) {
      lo = min(lo, s.x);
      hi = max(hi, s.y);
      tau_all += media[i].extinction * (s.y - s.x);
    }
  }
  vec3 through = transmittance(tau_all);
  float covered = 1.0 - dot(through, vec3(1.0 / 3.0));
  vec3 added = vec3(0.0);
  if (hi > lo) {
    int steps = max(int(frame.volume_params.z), 1);
    float dt = (hi - lo) / float(steps);
    float offset = fract(pixel_hash(gl_FragCoord.xy + 17.0) + frame.volume_params.w);
    for (int k = 0; k < steps; k++) {
      float a = lo + float(k) * dt;
      float u = fract(offset + float(k) * 0.61803398875);
      /* The step's mean extinction at its middle decides where its point goes. */
      vec3 mid = o + (a + 0.5 * dt) * d;
      float kappa = 0.0;
      for (int i = 0; i < count; i++) {
        if (medium_holds(media[i], mid)) {
          kappa += dot(media[i].extinction, vec3(1.0 / 3.0));
        }
      }
      float t, pdf;
      float kd = kappa * dt;
      if (kd > 1e-4) {
        float span = 1.0 - exp(-min(kd, 80.0));
        t = a - log(max(1.0 - u * span, 1e-30)) / kappa;
        pdf = kappa * exp(-min(kappa * (t - a), 80.0)) / span;
      }
      else {
        t = a + u * dt;
        pdf = 1.0 / dt;
      }
      vec3 x = o + t * d;
      /* What the media at x scatter of each light towards the camera, and emit. */
      vec3 source = vec3(0.0);
      vec3 scatter = vec3(0.0);
      for (int i = 0; i < count; i++) {
        if (medium_holds(media[i], x)) {
          source += media[i].emission;
          scatter += media[i].scatter;
        }
      }
      if (all(equal(source, vec3(0.0))) && all(equal(scatter, vec3(0.0)))) {
        continue;
      }
      for (int l = 0; l < frame.light_count; l++) {
        LightData L = lights[l];
        if (L.world != 0) {
          continue; /* the world's light comes from its SH below */
        }
        vec3 to_light;
        float irradiance;
        light_incident(L, x, to_light, irradiance);
        if (irradiance <= 0.0) {
          continue;
        }
        float visibility = (l < frame.shadowed_count) ?
                               shadow_visibility(L, x, to_light, to_light, 1.0, 1.0, FILTER_HARDWARE) :
                               1.0;
        if (visibility <= 0.0) {
          continue;
        }
        float cos_theta = dot(to_light, d);
        vec3 phased = vec3(0.0);
        for (int i = 0; i < count; i++) {
          if (medium_holds(media[i], x)) {
            phased += media[i].scatter * phase_hg(media[i].anisotropy, cos_theta);
          }
        }
        source += phased * L.color * (irradiance * visibility * L.volume_factor) *
                  light_transmittance(x, L, to_light);
      }
      /* The world's light, each medium's phase over its SH light (band l scaled by g^l),
       * through what the media let through along one direction of this sample's own. */
      vec3 world = vec3(0.0);
      for (int i = 0; i < count; i++) {
        if (medium_holds(media[i], x)) {
          float g = media[i].anisotropy;
          world += media[i].scatter * world_sh(d, vec2(g, g * g));
        }
      }
      if (any(greaterThan(world, vec3(0.0)))) {
        float v = fract(u * 7.3 + float(k) * 0.7548776662 + offset);
        float w = fract(pixel_hash(gl_FragCoord.xy + 53.0 + float(k)) + frame.volume_params.w);
        float cz = 1.0 - 2.0 * v, sz = sqrt(max(1.0 - cz * cz, 0.0));
        vec3 dir = vec3(sz * cos(2.0 * M_PI * w), sz * sin(2.0 * M_PI * w), cz);
        source += world * transmittance(optical_depth(x, dir, FAR_AWAY));
      }
      added += transmittance(optical_depth(o, d, t)) * source / pdf;
    }
  }
  out_transmit = vec4(through, 1.0 - covered);
  out_scatter = sanitize(vec4(max(added, vec3(0.0)), covered));
}
