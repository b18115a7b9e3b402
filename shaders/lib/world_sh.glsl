// requires:
#ifndef PENUMBRA_LIB_WORLD_SH
#define PENUMBRA_LIB_WORLD_SH

/* Reads the frame block's SH light (frame.world_color, frame.world_sh1..8): what the lit pass
 * and the volumes' march take of the world's light. */

/* The world's radiance around direction d from its SH coefficients, each band scaled by
 * g.x (band 1) and g.y (band 2): (1, 1) is the radiance itself, (2/3, 1/4) the cosine-lobe
 * convolution (irradiance / pi). */
vec3 world_sh(vec3 d, vec2 g)
{
  vec3 r = frame.world_color;
  r += g.x * 0.4886025 * (frame.world_sh1.xyz * d.y + frame.world_sh2.xyz * d.z + frame.world_sh3.xyz * d.x);
  r += g.y * (1.0925484 * (frame.world_sh4.xyz * d.x * d.y + frame.world_sh5.xyz * d.y * d.z +
                           frame.world_sh7.xyz * d.x * d.z) +
              0.3153916 * frame.world_sh6.xyz * (3.0 * d.z * d.z - 1.0) +
              0.5462742 * frame.world_sh8.xyz * (d.x * d.x - d.y * d.y));
  return max(r, vec3(0.0));
}

#endif /* PENUMBRA_LIB_WORLD_SH */
