/* Image textures as Blender's Image Texture node reads them: interpolation (0 Closest,
 * 1 Linear) and extension (0 Repeat, 1 Extend, 2 Clip, 3 Mirror) are applied here with
 * texelFetch, so they do not depend on the texture's sampler state. Images are uploaded as
 * scene-linear RGBA with straight alpha (engine/scene/textures.py). */

#ifndef MATERIAL_GLSL
#define MATERIAL_GLSL

#define EXTENSION_REPEAT 0
#define EXTENSION_EXTEND 1
#define EXTENSION_CLIP 2
#define EXTENSION_MIRROR 3

int wrap_mirror(int i, int n)
{
  int period = 2 * n;
  int m = ((i % period) + period) % period;
  return (m < n) ? m : period - 1 - m;
}

vec4 image_texel(sampler2D tex, ivec2 p, ivec2 size, int extension)
{
  if (extension == EXTENSION_CLIP) {
    if (any(lessThan(p, ivec2(0))) || any(greaterThanEqual(p, size))) {
      return vec4(0.0);
    }
  }
  else if (extension == EXTENSION_REPEAT) {
    p = ((p % size) + size) % size;
  }
  else if (extension == EXTENSION_MIRROR) {
    p = ivec2(wrap_mirror(p.x, size.x), wrap_mirror(p.y, size.y));
  }
  else {
    p = clamp(p, ivec2(0), size - 1);
  }
  return texelFetch(tex, p, 0);
}

/* mode: (interpolation, extension, use the alpha output, unused). */
vec4 sample_image(sampler2D tex, vec2 uv, ivec4 mode)
{
  ivec2 size = textureSize(tex, 0);
  vec2 st = uv * vec2(size);
  if (!(abs(st.x) < 1e7 && abs(st.y) < 1e7)) {
    return vec4(0.0); /* NaN or absurd coordinates */
  }
  if (mode.x == 0) {
    return image_texel(tex, ivec2(floor(st)), size, mode.y);
  }
  st -= 0.5;
  ivec2 i = ivec2(floor(st));
  vec2 f = st - floor(st);
  vec4 a = image_texel(tex, i, size, mode.y);
  vec4 b = image_texel(tex, i + ivec2(1, 0), size, mode.y);
  vec4 c = image_texel(tex, i + ivec2(0, 1), size, mode.y);
  vec4 d = image_texel(tex, i + ivec2(1, 1), size, mode.y);
  return mix(mix(a, b, f.x), mix(c, d, f.x), f.y);
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
               material.channel##_mode)

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

#endif
