// requires: nodes/common.glsl
#ifndef PENUMBRA_LIB_NODES_SHADER
#define PENUMBRA_LIB_NODES_SHADER

/* Shader sockets of a compiled node tree (engine/scene/nodetree.py): a closure is up to TWO
 * lobes, each the Principled parameters Penumbra shades with as sums weighted by how much of
 * that surface there is, plus the coverage and emission the lobes share:
 *   lobe a, lobe b   color, roughness, metallic, specular, normal: each x ``weight``
 *                    (specular: the dielectric's F0 from IOR, Specular IOR Level and
 *                    Specular Tint as rgb, untinted as a: node_principled_f0)
 *                    (a Transparent BSDF or an Emission adds no lobe)
 *   alpha            coverage (Transparent adds 0, every other shader 1 x its alpha)
 *   emission         weighted by coverage
 * A lone shader is lobe a. Mix Shader and Add Shader combine two closures with their factor,
 * which may come from any node: the compiler (which knows how many lobes each side can hold)
 * calls node_mix_shader / node_add_shader where the result holds one lobe (lobes summed:
 * one Principled surface with mixed parameters, as before), node_mix_split / node_add_split
 * where two single lobes become a and b, and node_mix_merge / node_add_merge beyond that:
 * Penumbra shades at most two lobes per pixel, so of three or four lobes the two most similar
 * (node_lobe_distance) merge, per pixel, into one with their weighted parameters, until two
 * are left. node_closure_resolve gives one set of parameters (the lobes summed: trees of one
 * lobe, and the shadow pass's alpha); node_closure_resolve_lobes the two lobes and their
 * weights (the lit pass under NODE_LOBES == 2).
 *
 * A Principled BSDF's coat (Coat Weight above 0 or linked: node_principled_coat) is the
 * closure's, not a lobe's: it lies over both lobes. Its parameters are sums weighted by the
 * coat's weight times the surface's share, as the lobes' are: coat (weight, roughness, IOR, 0),
 * coat_tint and coat_normal; a closure without a coat has weight 0 there. node_coat_keep
 * resolves them for the lit pass (NODE_COAT: node_coat_params, node_coat_tint,
 * node_coat_normal). The Thin Film (film) and the Sheen (sheen, sheen_tint: node_sheen_keep,
 * NODE_SHEEN) are the closure's too, with the same weighted sums. */

struct NodeLobe {
  vec3 color;
  float roughness;
  float metallic;
  vec4 specular;
  float weight;
  vec3 normal;
};

struct NodeClosure {
  NodeLobe a;
  NodeLobe b;
  float alpha;
  vec3 emission;
  vec4 coat; /* (weight, roughness, IOR, 0), each x the coat's weight */
  vec3 coat_tint;
  vec3 coat_normal;
  vec4 film; /* (weight, thickness, film IOR, base IOR), each x the film's weight: Thin Film */
  vec4 sheen; /* (weight, roughness, layered, 0), each x the sheen's weight: a Principled Sheen
              * (layered 1: over the lobes) or a Sheen BSDF (0: beside them) */
  vec3 sheen_tint; /* Sheen Tint x the sheen's weight */
  vec4 aniso; /* (tangent, ln k), each x the surface's coverage: anisotropy (lib/anisotropy.glsl) */
  vec4 sss; /* (Burley's d per channel x w, w): w the share of the diffuse that scatters below the
             * surface x the coverage (Subsurface Weight; lib/subsurface.glsl) */
  vec3 sss_exit; /* its light's share leaving towards the normal x w (1: Lambertian; node_sss_walk) */
};

NodeLobe node_lobe_empty()
{
  return NodeLobe(vec3(0.0), 0.0, 0.0, vec4(0.0), 0.0, vec3(0.0));
}

NodeClosure node_closure_empty()
{
  return NodeClosure(node_lobe_empty(), node_lobe_empty(), 0.0, vec3(0.0), vec4(0.0), vec3(0.0), vec3(0.0),
                     vec4(0.0), vec4(0.0), vec3(0.0), vec4(0.0), vec4(0.0), vec3(0.0));
}

/* The Principled BSDF's dielectric reflectance at normal incidence, as Blender's (Cycles'
 * principled closure, EEVEE's gpu_shader_material_principled.glsl): f0 from the IOR,
 * ((ior - 1) / (ior + 1))^2, scaled by 2 x Specular IOR Level (0.5 leaves it), times Specular
 * Tint, clamped to [0, 1] per channel (rgb); a: the untinted f0 (what decides whether the
 * surface has a Fresnel rim at all: Blender's F90 is 1 unless the IOR comes to 1). */
vec4 node_principled_f0(float ior, float level, vec4 tint)
{
  /* Every input finite and bounded first (materials.dielectric_f0 does the same), so no
   * product below is 0 x inf. */
  ior = isnan(ior) ? 1.5 : clamp(ior, 0.0, 1e6);
  level = isnan(level) ? 0.0 : clamp(level, 0.0, 1e6);
  vec3 t = vec3(isnan(tint.r) ? 0.0 : tint.r, isnan(tint.g) ? 0.0 : tint.g, isnan(tint.b) ? 0.0 : tint.b);
  float r = (ior - 1.0) / (ior + 1.0);
  float f0 = r * r * 2.0 * level;
  return vec4(clamp(f0 * clamp(t, 0.0, 1e6), 0.0, 1.0), clamp(f0, 0.0, 1.0));
}

NodeClosure node_principled(vec4 base, float metallic, float roughness, vec4 specular, float alpha,
                            vec3 emission, vec3 normal)
{
  float a = clamp(alpha, 0.0, 1.0);
  NodeClosure c = node_closure_empty();
  c.a = NodeLobe(base.rgb * a, roughness * a, metallic * a, specular * a, a, normal * a);
  c.alpha = a;
  c.emission = emission * a;
  return c;
}

/* The Principled BSDF ``c`` (node_principled) with its coat: Coat Weight, Roughness, IOR, Tint
 * and Normal, scaled by the surface's coverage as its lobe is. */
NodeClosure node_principled_coat(NodeClosure c, float weight, float roughness, float ior, vec4 tint, vec3 normal)
{
  float w = clamp(isnan(weight) ? 0.0 : weight, 0.0, 1.0) * c.alpha;
  float r = clamp(isnan(roughness) ? 0.0 : roughness, 0.0, 1.0);
  float eta = clamp(isnan(ior) ? 1.5 : ior, 1.0, 1e6);
  c.coat = vec4(w, w * r, w * eta, 0.0);
  vec3 t = vec3(isnan(tint.r) ? 0.0 : tint.r, isnan(tint.g) ? 0.0 : tint.g, isnan(tint.b) ? 0.0 : tint.b);
  c.coat_tint = w * clamp(t, 0.0, 1e6);
  c.coat_normal = w * normal;
  return c;
}

/* The Principled BSDF ``c`` with its Thin Film: Thickness (nm) and IOR over a base of IOR
 * ``ior`` (the BSDF's) as Specular IOR Level ``level`` adjusts it (Cycles: the IOR whose F0 is
 * 2 level times the IOR's), scaled by the surface's coverage. */
NodeClosure node_principled_film(NodeClosure c, float thickness, float film_ior, float ior, float level)
{
  float w = c.alpha;
  float d = clamp(isnan(thickness) ? 0.0 : thickness, 0.0, 1e5);
  float eta = clamp(isnan(film_ior) ? 1.33 : film_ior, 1.0, 1e6);
  float base = clamp(isnan(ior) ? 1.5 : ior, 1.0, 1e6);
  float r = (base - 1.0) / (base + 1.0);
  float f0 = clamp(r * r * 2.0 * clamp(isnan(level) ? 0.5 : level, 0.0, 1e6), 0.0, 0.99);
  base = (1.0 + sqrt(f0)) / (1.0 - sqrt(f0));
  c.film = vec4(w, w * d, w * eta, w * base);
  return c;
}

/* The Principled BSDF ``c`` with its Sheen: Weight, Roughness and Tint, scaled by the surface's
 * coverage. */
NodeClosure node_principled_sheen(NodeClosure c, float weight, float roughness, vec4 tint)
{
  float w = clamp(isnan(weight) ? 0.0 : weight, 0.0, 1e3) * c.alpha;
  float r = clamp(isnan(roughness) ? 0.0 : roughness, 0.0, 1.0);
  vec3 t = vec3(isnan(tint.r) ? 0.0 : tint.r, isnan(tint.g) ? 0.0 : tint.g, isnan(tint.b) ? 0.0 : tint.b);
  c.sheen = vec4(w, w * r, w, 0.0);
  c.sheen_tint = w * clamp(t, 0.0, 1e6);
  return c;
}

/* ``T`` turned about ``N`` by ``turns`` of a full turn (Rodrigues), as Cycles' rotate_around_axis. */
vec3 node_rotate_tangent(vec3 T, vec3 N, float turns)
{
  float a = 2.0 * NODE_PI * (isnan(turns) ? 0.0 : clamp(turns, -1e4, 1e4));
  float c = cos(a), s = sin(a);
  return T * c + cross(N, T) * s + N * (dot(N, T) * (1.0 - c));
}

/* Cycles' radial tangent (the Tangent node's Radial, and what the Principled BSDF's Tangent
 * takes unlinked: about Z): around ``axis`` (0 X, 1 Y, 2 Z) of the generated coordinates
 * ``g``, turned to the world as a normal is (``m``: the object's matrix), on the surface of ``N``. */
vec3 node_radial_tangent(vec3 g, mat3 m, vec3 N, int axis)
{
  vec3 d = g - 0.5;
  vec3 t = (axis == 0) ? vec3(0.0, -d.z, d.y) : (axis == 1) ? vec3(-d.z, 0.0, d.x) : vec3(-d.y, d.x, 0.0);
  t = transpose(inverse(m)) * t;
  vec3 c = cross(t, N);
  float cl = length(c);
  return (cl > 1e-12 && !isinf(cl)) ? cross(N, c / cl) : vec3(0.0);
}

/* The Principled BSDF ``c`` with its Anisotropic (0 to 1) and Anisotropic Rotation about ``N``
 * for ``tangent``: k = 1 / sqrt(1 - 0.9 Anisotropic), as Cycles' principled closure. */
NodeClosure node_principled_aniso(NodeClosure c, float anisotropic, float rotation, vec3 tangent, vec3 N)
{
  float a = clamp(isnan(anisotropic) ? 0.0 : anisotropic, 0.0, 1.0);
  vec3 T = node_rotate_tangent(tangent, N, rotation);
  c.aniso = c.alpha * vec4(T, -0.5 * log(1.0 - 0.9 * a));
  return c;
}

/* A Glossy BSDF ``c`` with its Anisotropy (-0.99 to 0.99) and Rotation about ``N`` for
 * ``tangent``: k = 1 / (1 + a) below 0, 1 - a above, as Cycles' glossy closure. */
NodeClosure node_glossy_aniso(NodeClosure c, float anisotropy, float rotation, vec3 tangent, vec3 N)
{
  float a = clamp(isnan(anisotropy) ? 0.0 : anisotropy, -0.99, 0.99);
  vec3 T = node_rotate_tangent(tangent, N, rotation);
  c.aniso = c.alpha * vec4(T, (a < 0.0) ? -log(1.0 + a) : log(1.0 - a));
  return c;
}

/* A Sheen BSDF (Microfiber) of ``color`` and ``roughness``: a sheen beside whatever it is mixed
 * or added with, as Cycles sums closures (not layered over them). */
NodeClosure node_sheen_bsdf(vec4 color, float roughness)
{
  NodeClosure c = node_closure_empty();
  c.alpha = 1.0;
  float r = clamp(isnan(roughness) ? 0.0 : roughness, 0.0, 1.0);
  vec3 t = vec3(isnan(color.r) ? 0.0 : color.r, isnan(color.g) ? 0.0 : color.g, isnan(color.b) ? 0.0 : color.b);
  c.sheen = vec4(1.0, r, 0.0, 0.0);
  c.sheen_tint = clamp(t, 0.0, 1e6);
  return c;
}

NodeClosure node_emission(vec4 color, float strength)
{
  NodeClosure c = node_closure_empty();
  c.alpha = 1.0;
  c.emission = color.rgb * strength;
  return c;
}

NodeClosure node_diffuse(vec4 color, vec3 normal)
{
  NodeClosure c = node_closure_empty();
  c.a = NodeLobe(color.rgb, 1.0, 0.0, vec4(0.0), 1.0, normal);
  c.alpha = 1.0;
  return c;
}

NodeClosure node_transparent()
{
  return node_closure_empty();
}

/* g x + f y, lobe by lobe (the weighted-parameter rule: merging two lobes adds their sums). */
NodeLobe node_lobe_mix(float g, NodeLobe x, float f, NodeLobe y)
{
  return NodeLobe(g * x.color + f * y.color, g * x.roughness + f * y.roughness, g * x.metallic + f * y.metallic,
                  g * x.specular + f * y.specular, g * x.weight + f * y.weight, g * x.normal + f * y.normal);
}

NodeLobe node_lobe_sum(NodeLobe x, NodeLobe y)
{
  return node_lobe_mix(1.0, x, 1.0, y);
}

/* What two closures weighted g and f share beyond their lobes, summed into ``c``: coverage,
 * emission, and the closure-wide layers (coat, Thin Film, Sheen). */
void node_shared_mix(float g, NodeClosure a, float f, NodeClosure b, inout NodeClosure c)
{
  c.alpha = g * a.alpha + f * b.alpha;
  c.emission = g * a.emission + f * b.emission;
  c.coat = g * a.coat + f * b.coat;
  c.coat_tint = g * a.coat_tint + f * b.coat_tint;
  c.coat_normal = g * a.coat_normal + f * b.coat_normal;
  c.film = g * a.film + f * b.film;
  c.sheen = g * a.sheen + f * b.sheen;
  c.sheen_tint = g * a.sheen_tint + f * b.sheen_tint;
  c.aniso = g * a.aniso + f * b.aniso;
  c.sss = g * a.sss + f * b.sss;
  c.sss_exit = g * a.sss_exit + f * b.sss_exit;
}

/* Closures whose lobes stay where they are: a with a, b with b. */
NodeClosure node_mix_shader_weights(float g, NodeClosure a, float f, NodeClosure b)
{
  NodeClosure c;
  c.a = node_lobe_mix(g, a.a, f, b.a);
  c.b = node_lobe_mix(g, a.b, f, b.b);
  node_shared_mix(g, a, f, b, c);
  return c;
}

NodeClosure node_mix_shader(float f, NodeClosure a, NodeClosure b)
{
  f = clamp(f, 0.0, 1.0);
  return node_mix_shader_weights(1.0 - f, a, f, b);
}

NodeClosure node_add_shader(NodeClosure a, NodeClosure b)
{
  return node_mix_shader_weights(1.0, a, 1.0, b);
}

/* Two closures of one lobe each: a's lobe becomes lobe a, b's lobe b. */
NodeClosure node_mix_split_weights(float g, NodeClosure a, float f, NodeClosure b)
{
  NodeLobe none = node_lobe_empty();
  NodeClosure c;
  c.a = node_lobe_mix(g, a.a, 0.0, none);
  c.b = node_lobe_mix(f, b.a, 0.0, none);
  node_shared_mix(g, a, f, b, c);
  return c;
}

NodeClosure node_mix_split(float f, NodeClosure a, NodeClosure b)
{
  f = clamp(f, 0.0, 1.0);
  return node_mix_split_weights(1.0 - f, a, f, b);
}

NodeClosure node_add_split(NodeClosure a, NodeClosure b)
{
  return node_mix_split_weights(1.0, a, 1.0, b);
}

/* How unlike two lobes are: their parameters' differences (an empty lobe is like any). */
float node_lobe_distance(NodeLobe x, NodeLobe y)
{
  if (!(x.weight > 1e-6) || !(y.weight > 1e-6)) {
    return -1.0;
  }
  float ix = 1.0 / x.weight, iy = 1.0 / y.weight;
  float nx = length(x.normal), ny = length(y.normal);
  float bend = (nx > 1e-12 && ny > 1e-12) ? 0.5 * (1.0 - dot(x.normal, y.normal) / (nx * ny)) : 0.0;
  vec3 dc = abs(x.color * ix - y.color * iy);
  /* F0 counts as Specular IOR Level would (0.08 per unit of level at IOR 1.5). */
  vec3 ds = abs(x.specular.rgb * ix - y.specular.rgb * iy) * 12.5;
  float d = abs(x.roughness * ix - y.roughness * iy) + abs(x.metallic * ix - y.metallic * iy) +
            (ds.r + ds.g + ds.b) / 3.0 + (dc.r + dc.g + dc.b) / 3.0 + bend;
  return isnan(d) ? 0.0 : d;
}

/* Three lobes to two: the two most similar merge. */
void node_lobes_reduce3(NodeLobe x, NodeLobe y, NodeLobe z, out NodeLobe a, out NodeLobe b)
{
  float dxy = node_lobe_distance(x, y), dxz = node_lobe_distance(x, z), dyz = node_lobe_distance(y, z);
  if (dxy <= dxz && dxy <= dyz) {
    a = node_lobe_sum(x, y);
    b = z;
  }
  else if (dxz <= dyz) {
    a = node_lobe_sum(x, z);
    b = y;
  }
  else {
    a = x;
    b = node_lobe_sum(y, z);
  }
}

/* The four lobes of two two-lobe closures (weighted g and f) merged, most similar first,
 * down to two. */
NodeClosure node_mix_merge_weights(float g, NodeClosure a, float f, NodeClosure b)
{
  NodeLobe none = node_lobe_empty();
  NodeLobe w = node_lobe_mix(g, a.a, 0.0, none), x = node_lobe_mix(g, a.b, 0.0, none);
  NodeLobe y = node_lobe_mix(f, b.a, 0.0, none), z = node_lobe_mix(f, b.b, 0.0, none);
  float dwx = node_lobe_distance(w, x), dwy = node_lobe_distance(w, y), dwz = node_lobe_distance(w, z);
  float dxy = node_lobe_distance(x, y), dxz = node_lobe_distance(x, z), dyz = node_lobe_distance(y, z);
  float m = min(min(min(dwx, dwy), min(dwz, dxy)), min(dxz, dyz));
  NodeLobe p, q, r;
  if (m == dwx) {
    p = node_lobe_sum(w, x), q = y, r = z;
  }
  else if (m == dwy) {
    p = node_lobe_sum(w, y), q = x, r = z;
  }
  else if (m == dwz) {
    p = node_lobe_sum(w, z), q = x, r = y;
  }
  else if (m == dxy) {
    p = node_lobe_sum(x, y), q = w, r = z;
  }
  else if (m == dxz) {
    p = node_lobe_sum(x, z), q = w, r = y;
  }
  else {
    p = node_lobe_sum(y, z), q = w, r = x;
  }
  NodeClosure c;
  node_lobes_reduce3(p, q, r, c.a, c.b);
  node_shared_mix(g, a, f, b, c);
  return c;
}

NodeClosure node_mix_merge(float f, NodeClosure a, NodeClosure b)
{
  f = clamp(f, 0.0, 1.0);
  return node_mix_merge_weights(1.0 - f, a, f, b);
}

NodeClosure node_add_merge(NodeClosure a, NodeClosure b)
{
  return node_mix_merge_weights(1.0, a, 1.0, b);
}

vec3 node_finite3(vec3 v, float limit)
{
  return vec3(isnan(v.x) ? 0.0 : clamp(v.x, -limit, limit), isnan(v.y) ? 0.0 : clamp(v.y, -limit, limit),
              isnan(v.z) ? 0.0 : clamp(v.z, -limit, limit));
}

/* The sums back as parameters: ``weight`` divides roughness and metallic, ``coverage`` colour
 * and specular (a surface with no reflecting part: black, rough, no specular); NaN or
 * infinite inputs (a division the tree did, an absurd constant) draw finite. */
void node_lobe_resolve(NodeLobe c, float coverage, inout vec4 base, inout float roughness, inout float metallic,
                       inout vec4 specular, inout vec3 normal)
{
  float nl = length(c.normal);
  normal = (nl > 1e-12 && !isinf(nl)) ? c.normal / nl : normal;
  float inv = (coverage > 1e-6) ? 1.0 / coverage : 0.0;
  float winv = (c.weight > 1e-6) ? 1.0 / c.weight : 0.0;
  base = vec4(node_finite3(c.color * inv, 1e6), 1.0);
  specular = vec4(node_finite3(c.specular.rgb * inv, 1e6), node_finite3(vec3(c.specular.a * inv), 1e6).x);
  roughness = node_finite3(vec3((c.weight > 1e-6) ? c.roughness * winv : 1.0), 1.0).x;
  metallic = node_finite3(vec3(c.metallic * winv), 1.0).x;
}

/* One set of parameters: the lobes summed. */
void node_closure_resolve(NodeClosure c, inout vec4 base, inout float roughness, inout float metallic,
                          inout vec4 specular, inout float alpha, inout vec3 emission, inout vec3 normal)
{
  float coverage = clamp(c.alpha, 0.0, 1.0);
  node_lobe_resolve(node_lobe_sum(c.a, c.b), coverage, base, roughness, metallic, specular, normal);
  float inv = (coverage > 1e-6) ? 1.0 / coverage : 0.0;
  emission = node_finite3(c.emission * inv, 1e20);
  alpha = node_finite3(vec3(coverage), 1.0).x;
}

/* Two lobes, each its own parameters (divided by its own weight), and their weights over the
 * coverage (the lit pass's colour is the lobes' shading summed by these; an Add Shader's
 * lobes may sum above 1, as in Blender). */
void node_closure_resolve_lobes(NodeClosure c, inout vec4 base, inout float roughness, inout float metallic,
                                inout vec4 specular, inout float alpha, inout vec3 emission, inout vec3 normal,
                                inout vec4 base_b, inout float roughness_b, inout float metallic_b,
                                inout vec4 specular_b, inout vec3 normal_b, out vec2 weights)
{
  float coverage = clamp(c.alpha, 0.0, 1.0);
  node_lobe_resolve(c.a, c.a.weight, base, roughness, metallic, specular, normal);
  node_lobe_resolve(c.b, c.b.weight, base_b, roughness_b, metallic_b, specular_b, normal_b);
  float inv = (coverage > 1e-6) ? 1.0 / coverage : 0.0;
  weights = node_finite3(vec3(c.a.weight * inv, c.b.weight * inv, 0.0), 1e6).xy;
  weights = max(weights, vec2(0.0));
  emission = node_finite3(c.emission * inv, 1e20);
  alpha = node_finite3(vec3(coverage), 1.0).x;
}

/* The closure's coat as parameters (NODE_COAT, lib/lit_inputs.glsl): (its share of the surface,
 * roughness, IOR, 0), its tint and normal (0: the surface's). */
vec4 node_coat_params = vec4(0.0, 0.0, 1.5, 0.0);
vec3 node_coat_tint = vec3(1.0);
vec3 node_coat_normal = vec3(0.0);

void node_coat_keep(NodeClosure c)
{
  float w = c.coat.x;
  float coverage = clamp(c.alpha, 0.0, 1.0);
  float winv = (w > 1e-6) ? 1.0 / w : 0.0;
  node_coat_params = vec4(node_finite3(vec3((coverage > 1e-6) ? w / coverage : 0.0), 1.0).x,
                          node_finite3(vec3(c.coat.y * winv), 1.0).x, max(c.coat.z * winv, 1.0), 0.0);
  if (!(w > 1e-6)) {
    node_coat_params = vec4(0.0, 0.0, 1.5, 0.0);
  }
  node_coat_tint = (w > 1e-6) ? clamp(node_finite3(c.coat_tint * winv, 1e6), 0.0, 1.0) : vec3(1.0);
  float nl = length(c.coat_normal);
  node_coat_normal = (nl > 1e-12 && !isinf(nl)) ? c.coat_normal / nl : vec3(0.0);
}

/* The closure's Thin Film as parameters (NODE_FILM, lib/lit_inputs.glsl): (its share of the
 * surface, thickness, film IOR, base IOR). */
vec4 node_film_params = vec4(0.0, 0.0, 1.33, 1.5);

void node_film_keep(NodeClosure c)
{
  float w = c.film.x;
  float coverage = clamp(c.alpha, 0.0, 1.0);
  float winv = (w > 1e-6) ? 1.0 / w : 0.0;
  node_film_params = (w > 1e-6) ? vec4(node_finite3(vec3(w / max(coverage, 1e-6)), 1.0).x,
                                       node_finite3(c.film.yzw * winv, 1e5)) :
                                  vec4(0.0, 0.0, 1.33, 1.5);
}

/* The closure's Sheen as parameters (NODE_SHEEN, lib/lit_inputs.glsl): its colour (Sheen Weight x
 * Tint, over the surface) and roughness in w; node_sheen_layered: the share of it that lies over
 * the lobes (a Principled BSDF's) rather than beside them (a Sheen BSDF's). */
vec4 node_sheen_params = vec4(0.0);
float node_sheen_layered = 1.0;

void node_sheen_keep(NodeClosure c)
{
  float w = c.sheen.x;
  float coverage = clamp(c.alpha, 0.0, 1.0);
  float winv = (w > 1e-6) ? 1.0 / w : 0.0;
  float share = (coverage > 1e-6) ? w / coverage : 0.0;
  node_sheen_params = (w > 1e-6) ? vec4(node_finite3(c.sheen_tint * winv * share, 1e6),
                                        node_finite3(vec3(c.sheen.y * winv), 1.0).x) :
                                   vec4(0.0);
  node_sheen_layered = (w > 1e-6) ? node_finite3(vec3(c.sheen.z * winv), 1.0).x : 1.0;
}

/* Burley's profile distance d per channel (world units) of a subsurface Radius x Scale, as
 * Cycles scales both its Christensen-Burley and Random Walk radii (bssrdf_setup_radius: the
 * mean free path r / 4 pi), each finite and within [0, 1e4]. */
vec3 node_sss_distance(vec3 radius, float scale)
{
  vec3 d = max(radius, vec3(0.0)) * clamp(isnan(scale) ? 0.0 : scale, 0.0, 1e6) * 0.07957747154594767;
  return node_finite3(d, 1e4);
}

/* Cycles' Random Walk as Burley's profile, fitted to Cycles itself (tools/fit_random_walk.py:
 * a plane lit across a hard edge, Cycles' random walk against the plain diffuse convolved with
 * the profile, d and amplitude fitted per albedo A from 0.05 to 0.9; the fit's residual 0.3-0.4 %
 * of the lit light). Its walk spreads the light k(A) times Cycles' mean free path, 2.5 at A = 0
 * to 14 at 0.9 (within 4.4 %), and leaves the surface unlike a Lambertian one: c0(A) of it
 * towards the normal (0.77 to 0.96, within 1.4 %) and more at grazing angles, c0 + 3 (1 - c0)
 * (1 - cos), which keeps its albedo (lib/subsurface.glsl subsurface_exit). Returns (k, c0) per
 * channel as (x, y, z) pairs: the distance's factor in ``k``, c0 in ``exit``. */
void node_sss_walk(vec3 albedo, out vec3 k, out vec3 exit)
{
  vec3 A = clamp(albedo, 0.0, 1.0);
  k = 2.545 + A * (4.526 + A * 9.2);
  exit = 0.768 + 0.209 * A;
}

/* The subsurface of ``c``'s first lobe: Radius x Scale, Christensen-Burley's (``walk`` 0) or
 * Cycles' Random Walk as the profile it fits (``walk`` 1, node_sss_walk), its share ``w``. */
NodeClosure node_sss_set(NodeClosure c, float w, vec3 radius, float scale, float walk)
{
  vec3 d = node_sss_distance(radius, scale);
  vec3 exit = vec3(1.0);
  if (walk > 0.5) {
    vec3 k;
    node_sss_walk(c.a.color / max(c.a.weight, 1e-6), k, exit);
    d *= k;
    exit = mix(vec3(1.0), exit, vec3(greaterThan(d, vec3(0.0)))); /* no walk: a plain diffuse */
  }
  c.sss = vec4(w * node_finite3(d, 1e4), w);
  c.sss_exit = w * exit;
  return c;
}

/* The Principled BSDF ``c`` with its Subsurface: Weight (the share of the diffuse that
 * scatters below the surface), Radius x Scale and its method, over the surface's coverage. */
NodeClosure node_principled_sss(NodeClosure c, float weight, vec3 radius, float scale, float walk)
{
  return node_sss_set(c, clamp(isnan(weight) ? 0.0 : weight, 0.0, 1.0) * c.alpha, radius, scale, walk);
}

/* A Subsurface Scattering node: a diffuse of ``color`` all of which scatters below the surface
 * (Radius x Scale, its method). */
NodeClosure node_subsurface(vec4 color, float scale, vec3 radius, vec3 normal, float walk)
{
  return node_sss_set(node_diffuse(color, normal), 1.0, radius, scale, walk);
}

/* The closure's Subsurface as parameters (NODE_SSS, lib/lit_inputs.glsl): Burley's d per
 * channel and the share of the diffuse that scatters below the surface; how its light leaves
 * (node_sss_walk's c0, 1: Lambertian). */
vec4 node_sss_params = vec4(0.0);
vec3 node_sss_exit = vec3(1.0);

void node_sss_keep(NodeClosure c)
{
  float w = c.sss.w;
  float coverage = clamp(c.alpha, 0.0, 1.0);
  node_sss_params = (w > 1e-6) ? vec4(node_finite3(c.sss.xyz / w, 1e4), clamp(w / max(coverage, 1e-6), 0.0, 1.0)) :
                                 vec4(0.0);
  node_sss_exit = (w > 1e-6) ? clamp(c.sss_exit / w, 0.0, 1.0) : vec3(1.0);
}

/* The closure's anisotropy as parameters (NODE_ANISO, lib/lit_inputs.glsl): its tangent
 * direction (0: none) and ln k over the surface (lib/anisotropy.glsl). */
vec4 node_aniso_params = vec4(0.0);

void node_aniso_keep(NodeClosure c)
{
  float coverage = clamp(c.alpha, 0.0, 1.0);
  float tl = length(c.aniso.xyz);
  vec3 T = (tl > 1e-12 && !isinf(tl)) ? c.aniso.xyz / tl : vec3(0.0);
  float k = (coverage > 1e-6) ? c.aniso.w / coverage : 0.0;
  node_aniso_params = vec4(T, node_finite3(vec3(k), 10.0).x);
}

#endif /* PENUMBRA_LIB_NODES_SHADER */
