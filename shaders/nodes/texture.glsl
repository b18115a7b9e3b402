/* Simple procedural textures (Blender manual: Checker Texture, Gradient Texture). Blender's
 * hashed textures (Noise, Voronoi, ...) live in their own texture_*.glsl files. */

#ifndef NODE_TEXTURE_GLSL
#define NODE_TEXTURE_GLSL

/* x: Fac (1 on color1's cells). */
float node_checker(vec3 p, float scale)
{
  p *= scale;
  p = (p + 0.000001) * 0.999999; /* cell edges on whole coordinates fall one way */
  if (!all(lessThan(abs(p), vec3(1e9)))) {
    return 0.0;
  }
  int xi = int(abs(floor(p.x)));
  int yi = int(abs(floor(p.y)));
  int zi = int(abs(floor(p.z)));
  return ((xi % 2 == yi % 2) == (zi % 2 == 1)) ? 1.0 : 0.0;
}

/* Gradient: 0 Linear, 1 Quadratic, 2 Easing, 3 Diagonal, 4 Radial, 5 Quadratic Sphere,
 * 6 Spherical; the result clamped to [0, 1]. */
float node_gradient(const int type, vec3 p)
{
  float g = 0.0;
  switch (type) {
    case 0: g = p.x; break;
    case 1: {
      float r = max(p.x, 0.0);
      g = r * r;
      break;
    }
    case 2: {
      float r = clamp(p.x, 0.0, 1.0);
      float t = r * r;
      g = 3.0 * t - 2.0 * t * r;
      break;
    }
    case 3: g = (p.x + p.y) * 0.5; break;
    case 4: g = atan(p.y, p.x) / (2.0 * NODE_PI) + 0.5; break;
    case 5: {
      float r = max(0.999999 - length(p), 0.0);
      g = r * r;
      break;
    }
    case 6: g = max(0.999999 - length(p), 0.0); break;
  }
  return clamp(g, 0.0, 1.0);
}

#endif
