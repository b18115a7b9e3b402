// requires:
#ifndef PENUMBRA_LIB_MATERIAL
#define PENUMBRA_LIB_MATERIAL

/* Image textures as Blender's Image Texture node reads them. The textures are Blender's own
 * (gpu.texture.from_image: colour-managed to scene linear, with its mipmaps), filtered here
 * with texelFetch so the result does not depend on a sampler state: interpolation (0 Closest,
 * 1 Linear) and extension (0 Repeat, 1 Extend, 2 Clip, 3 Mirror) are applied at every mip
 * level. Linear minifies trilinearly from the pixel's footprint (the uv derivatives), with up
 * to IMAGE_MAX_ANISOTROPY trilinear probes along the footprint's long axis (anisotropic
 * filtering as the texture units of GPUs do it); Closest reads the full-size image. A texture
 * Blender stores premultiplied (a float image whose alpha mode is not Straight) is divided by
 * its alpha after filtering, so the node's Color output is straight, as in EEVEE. NaN texels
 * read as 0 and infinite ones as +-65504. */

#define EXTENSION_REPEAT 0
#define EXTENSION_EXTEND 1
#define EXTENSION_CLIP 2
#define EXTENSION_MIRROR 3
#define IMAGE_MAX_ANISOTROPY 8

/* i modulo n (> 0) in [0, n), from remainders of non-negative operands only: GLSL leaves %
 * undefined when an operand is negative (drivers differ), and an index left of the image or of
 * an equirectangular seam is -1. */
int wrap_repeat(int i, int n)
{
  if (i >= 0) {
    return i % n;
  }
  int m = (-i) % n;
  return (m == 0) ? 0 : n - m;
}

int wrap_mirror(int i, int n)
{
  int period = 2 * n;
  int m = wrap_repeat(i, period);
  return (m < n) ? m : period - 1 - m;
}

/* A texel index along an axis of ``n`` texels under ``extension``; -1 outside (Clip). */
int wrap_index(int i, int n, int extension)
{
  if (extension == EXTENSION_REPEAT) {
    return wrap_repeat(i, n);
  }
  if (extension == EXTENSION_MIRROR) {
    return wrap_mirror(i, n);
  }
  if (extension == EXTENSION_CLIP) {
    return (i < 0 || i >= n) ? -1 : i;
  }
  return clamp(i, 0, n - 1);
}

vec4 texel_or_zero(sampler2D tex, int x, int y, int level)
{
  return (x < 0 || y < 0) ? vec4(0.0) : texelFetch(tex, ivec2(x, y), level);
}

/* Bilinear at mip ``level`` between its texel centres; ``uv`` in [0, 1] image units. The
 * four texels' indices are wrapped once per axis. The level's size is the full size halved
 * ``level`` times (OpenGL's rule for a mip chain), not textureSize at that level: with a level
 * that differs between the pixels of one quad (a wide view's background, where the footprint
 * crosses a whole level), llvmpipe answered every pixel with one pixel's size, and the others
 * read out of their level: black or sky texels in the ground at 170 degrees. */
vec4 image_bilinear(sampler2D tex, vec2 uv, int level, int extension)
{
  ivec2 size = max(textureSize(tex, 0) >> level, ivec2(1));
  vec2 st = uv * vec2(size) - 0.5;
  ivec2 i = ivec2(floor(st));
  vec2 f = st - floor(st);
  int x0 = wrap_index(i.x, size.x, extension);
  int x1 = wrap_index(i.x + 1, size.x, extension);
  int y0 = wrap_index(i.y, size.y, extension);
  int y1 = wrap_index(i.y + 1, size.y, extension);
  vec4 a = texel_or_zero(tex, x0, y0, level);
  vec4 b = texel_or_zero(tex, x1, y0, level);
  vec4 c = texel_or_zero(tex, x0, y1, level);
  vec4 d = texel_or_zero(tex, x1, y1, level);
  return mix(mix(a, b, f.x), mix(c, d, f.x), f.y);
}

/* Between the two mip levels around ``lod`` (0: the full-size image). */
vec4 image_trilinear(sampler2D tex, vec2 uv, float lod, int levels, int extension)
{
  lod = clamp(lod, 0.0, float(levels - 1));
  int l0 = int(floor(lod));
  float f = lod - float(l0);
  vec4 a = image_bilinear(tex, uv, l0, extension);
  if (f <= 0.0 || l0 + 1 >= levels) {
    return a;
  }
  return mix(a, image_bilinear(tex, uv, l0 + 1, extension), f);
}

/* mode: (interpolation, extension, use the alpha output, component); ``duv_dx``, ``duv_dy``:
 * how uv changes from one pixel to the next (the footprint). */
vec4 sample_image_grad(sampler2D tex, vec2 uv, vec2 duv_dx, vec2 duv_dy, ivec4 mode, bool premultiplied)
{
  ivec2 size = textureSize(tex, 0);
  vec2 st = uv * vec2(size);
  if (!(abs(st.x) < 1e7 && abs(st.y) < 1e7)) {
    return vec4(0.0); /* NaN or absurd coordinates */
  }
  vec4 t;
  if (mode.x == 0) {
    ivec2 p = ivec2(floor(st));
    t = texel_or_zero(tex, wrap_index(p.x, size.x, mode.y), wrap_index(p.y, size.y, mode.y), 0);
  }
  else {
    /* The footprint's axes in full-size texels. */
    vec2 ax = duv_dx * vec2(size);
    vec2 ay = duv_dy * vec2(size);
    float lx = length(ax);
    float ly = length(ay);
    float major = max(lx, ly);
    int levels = textureQueryLevels(tex);
    if (!(major > 1.0) || levels <= 1 || !(major < 1e7)) {
      t = image_bilinear(tex, uv, 0, mode.y); /* magnified (or no footprint): the full-size image */
    }
    else {
      float minor = min(lx, ly);
      /* Probes: the footprint's aspect ratio, rounded (a nearly round footprint takes one). */
      int n = int(clamp(floor(major / max(minor, 1e-6) + 0.5), 1.0, float(IMAGE_MAX_ANISOTROPY)));
      float lod = log2(major / float(n));
      vec2 axis = ((lx >= ly) ? duv_dx : duv_dy);
      t = vec4(0.0);
      for (int k = 0; k < n; k++) {
        t += image_trilinear(tex, uv + axis * ((float(k) + 0.5) / float(n) - 0.5), lod, levels, mode.y);
      }
      t /= float(n);
    }
  }
  if (premultiplied && t.a > 0.0) {
    t.rgb /= t.a;
  }
  /* A float image may hold NaN or infinite texels (and its mipmaps spread them): NaN reads as
   * 0, infinities as the half-float limit, so the frame stays finite. */
  t = mix(t, vec4(0.0), isnan(t));
  return clamp(t, vec4(-65504.0), vec4(65504.0));
}

vec4 sample_image(sampler2D tex, vec2 uv, ivec4 mode, bool premultiplied)
{
  return sample_image_grad(tex, uv, dFdx(uv), dFdy(uv), mode, premultiplied);
}

vec2 texture_uv(vec2 uv, vec4 row_u, vec4 row_v)
{
  vec3 h = vec3(uv, 1.0);
  return vec2(dot(row_u.xyz, h), dot(row_v.xyz, h));
}

/* A colour channel: the image's colour (or its alpha as grey). */
#define SAMPLE_COLOR(channel, uv) \
  sample_image(tex_##channel, \
               texture_uv(uv, material.channel##_uv_u, material.channel##_uv_v), \
               material.channel##_mode, \
               (image_premultiplied & IMAGE_BIT_##channel) != 0)

/* A value channel: one component through a Separate Color node (mode.w 1-3: R, G, B), the
 * alpha output, or the colour converted to a value as Blender does (Rec.709 luminance). */
float sample_value(vec4 texel, ivec4 mode)
{
  if (mode.w != 0) {
    return texel[mode.w - 1];
  }
  return (mode.z != 0) ? texel.a : dot(texel.rgb, vec3(0.2126, 0.7152, 0.0722));
}

#define SAMPLE_VALUE(channel, uv) sample_value(SAMPLE_COLOR(channel, uv), material.channel##_mode)

/* A well-mixed per-pixel value in [0, 1) (Wang hash of the pixel's integer coordinates). */
float pixel_hash(vec2 frag)
{
  uvec2 p = uvec2(floor(frag));
  uint h = p.x * 1973u + p.y * 9277u;
  h = (h ^ 61u) ^ (h >> 16);
  h *= 9u;
  h ^= h >> 4;
  h *= 0x27d4eb2du;
  h ^= h >> 15;
  return float(h >> 8) / 16777216.0;
}

/* Two uniforms in [0, 1)^2 for this pixel and the frame's sample ``sample_index``: the R2
 * sequence (Roberts 2018) over the samples, shifted per pixel by pixel_hash salted with ``salt``
 * (a Cranley-Patterson rotation), so any run of a pixel's samples covers the square evenly. */
vec2 pixel_r2(float salt, int sample_index)
{
  vec2 shift = vec2(pixel_hash(gl_FragCoord.xy + salt), pixel_hash(gl_FragCoord.xy + salt + 101.0));
  return fract(shift + float(sample_index) * vec2(0.7548776662, 0.5698402910));
}

#endif /* PENUMBRA_LIB_MATERIAL */
