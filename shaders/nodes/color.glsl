// requires: nodes/common.glsl
#ifndef PENUMBRA_LIB_NODES_COLOR
#define PENUMBRA_LIB_NODES_COLOR

/* Colour nodes (Blender manual: Mix Color, Hue/Saturation/Value, Invert Color, Gamma,
 * Brightness/Contrast). The Mix node's blend modes take ``mode`` as a literal
 * (NODE_BLEND_* in engine/scene/nodetree.py); the result keeps A's alpha, as Blender's does. */

float node_dodge(float a, float b, float f)
{
  if (a == 0.0) {
    return 0.0;
  }
  float t = 1.0 - f * b;
  return (t <= 0.0) ? 1.0 : min(a / t, 1.0);
}

float node_burn(float a, float b, float f)
{
  float t = (1.0 - f) + f * b;
  return (t <= 0.0) ? 0.0 : clamp(1.0 - (1.0 - a) / t, 0.0, 1.0);
}

float node_overlay(float a, float b, float f)
{
  float fm = 1.0 - f;
  return (a < 0.5) ? a * (fm + 2.0 * f * b) : 1.0 - (fm + 2.0 * f * (1.0 - b)) * (1.0 - a);
}

vec4 node_mix_color(const int mode, float f, vec4 a, vec4 b)
{
  float fm = 1.0 - f;
  vec3 x = a.rgb, y = b.rgb, r = x;
  switch (mode) {
    case 0: r = mix(x, y, f); break;                                 /* Mix */
    case 1: r = mix(x, min(x, y), f); break;                         /* Darken */
    case 2: r = mix(x, x * y, f); break;                             /* Multiply */
    case 3: r = vec3(node_burn(x.r, y.r, f), node_burn(x.g, y.g, f), node_burn(x.b, y.b, f)); break;
    case 4: r = mix(x, max(x, y), f); break;                         /* Lighten */
    case 5: r = 1.0 - (fm + f * (1.0 - y)) * (1.0 - x); break;       /* Screen */
    case 6: r = vec3(node_dodge(x.r, y.r, f), node_dodge(x.g, y.g, f), node_dodge(x.b, y.b, f)); break;
    case 7: r = mix(x, x + y, f); break;                             /* Add */
    case 8: r = vec3(node_overlay(x.r, y.r, f), node_overlay(x.g, y.g, f), node_overlay(x.b, y.b, f)); break;
    case 9: {                                                        /* Soft Light */
      vec3 scr = 1.0 - (1.0 - y) * (1.0 - x);
      r = fm * x + f * ((1.0 - x) * y * x + x * scr);
      break;
    }
    case 10: r = x + f * (2.0 * (y - 0.5)); break;                   /* Linear Light */
    case 11: r = mix(x, abs(x - y), f); break;                       /* Difference */
    case 12: r = max(mix(x, x + y - 2.0 * x * y, f), 0.0); break;    /* Exclusion */
    case 13: r = mix(x, x - y, f); break;                            /* Subtract */
    case 14: r = fm * x + f * node_safe_divide3(x, y); break;        /* Divide */
    case 15: {                                                       /* Hue */
      vec4 h2 = node_rgb_to_hsv(b);
      if (h2.y != 0.0) {
        vec4 h = node_rgb_to_hsv(a);
        h.x = h2.x;
        r = mix(x, node_hsv_to_rgb(h).rgb, f);
      }
      break;
    }
    case 16: {                                                       /* Saturation */
      vec4 h = node_rgb_to_hsv(a);
      if (h.y != 0.0) {
        h.y = fm * h.y + f * node_rgb_to_hsv(b).y;
        r = node_hsv_to_rgb(h).rgb;
      }
      break;
    }
    case 17: {                                                       /* Value */
      vec4 h = node_rgb_to_hsv(a);
      h.z = fm * h.z + f * node_rgb_to_hsv(b).z;
      r = node_hsv_to_rgb(h).rgb;
      break;
    }
    case 18: {                                                       /* Color */
      vec4 h2 = node_rgb_to_hsv(b);
      if (h2.y != 0.0) {
        vec4 h = node_rgb_to_hsv(a);
        h.xy = h2.xy;
        r = mix(x, node_hsv_to_rgb(h).rgb, f);
      }
      break;
    }
  }
  return vec4(r, a.a);
}

vec4 node_hue_saturation(float hue, float sat, float value, float f, vec4 c)
{
  vec4 h = node_rgb_to_hsv(c);
  h.x = fract(h.x + hue + 0.5);
  h.y = clamp(h.y * sat, 0.0, 1.0);
  h.z = h.z * value;
  return mix(c, node_hsv_to_rgb(h), f);
}

vec4 node_invert(float f, vec4 c)
{
  return vec4(mix(c.rgb, 1.0 - c.rgb, f), c.a);
}

vec4 node_gamma(vec4 c, float g)
{
  return vec4((c.r > 0.0) ? node_pow(c.r, g) : c.r,
              (c.g > 0.0) ? node_pow(c.g, g) : c.g,
              (c.b > 0.0) ? node_pow(c.b, g) : c.b,
              c.a);
}

vec4 node_bright_contrast(vec4 c, float bright, float contrast)
{
  float a = 1.0 + contrast;
  float b = bright - contrast * 0.5;
  return vec4(max(a * c.rgb + b, 0.0), c.a);
}

/* Separate / Combine Color: 0 RGB, 1 HSV, 2 HSL. */
vec4 node_separate_color(const int mode, vec4 c)
{
  return (mode == 1) ? node_rgb_to_hsv(c) : (mode == 2) ? node_rgb_to_hsl(c) : c;
}

vec4 node_combine_color(const int mode, float x, float y, float z)
{
  vec4 c = vec4(x, y, z, 1.0);
  return (mode == 1) ? node_hsv_to_rgb(c) : (mode == 2) ? node_hsl_to_rgb(c) : c;
}

#endif /* PENUMBRA_LIB_NODES_COLOR */
