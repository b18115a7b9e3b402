/* Shader sockets of a compiled node tree (engine/scene/nodetree.py): a closure is the
 * Principled parameters Penumbra shades with, summed with weights so Mix Shader and Add
 * Shader combine them per pixel (the factor may come from any node):
 *   color, specular, emission   weighted by coverage (a Transparent BSDF adds none)
 *   roughness, metallic         weighted by ``weight``, how much reflecting surface there is
 *   alpha                       coverage (Transparent adds 0, every other shader 1 x its alpha)
 *   normal                      weighted by ``weight`` (a surface's shading normal)
 * node_closure_resolve divides the sums back into one set of parameters. This is Penumbra's
 * limit: a mix of two lobes is one Principled surface with mixed parameters, per pixel. */

#ifndef NODE_SHADER_GLSL
#define NODE_SHADER_GLSL

struct NodeClosure {
  vec3 color;
  float roughness;
  float metallic;
  float specular;
  float weight;
  float alpha;
  vec3 emission;
  vec3 normal;
};

NodeClosure node_closure_empty()
{
  return NodeClosure(vec3(0.0), 0.0, 0.0, 0.0, 0.0, 0.0, vec3(0.0), vec3(0.0));
}

NodeClosure node_principled(vec4 base, float metallic, float roughness, float specular, float alpha,
                            vec3 emission, vec3 normal)
{
  float a = clamp(alpha, 0.0, 1.0);
  return NodeClosure(base.rgb * a, roughness * a, metallic * a, specular * a, a, a, emission * a, normal * a);
}

NodeClosure node_emission(vec4 color, float strength)
{
  return NodeClosure(vec3(0.0), 0.0, 0.0, 0.0, 0.0, 1.0, color.rgb * strength, vec3(0.0));
}

NodeClosure node_diffuse(vec4 color, vec3 normal)
{
  return NodeClosure(color.rgb, 1.0, 0.0, 0.0, 1.0, 1.0, vec3(0.0), normal);
}

NodeClosure node_transparent()
{
  return node_closure_empty();
}

NodeClosure node_mix_shader(float f, NodeClosure a, NodeClosure b)
{
  f = clamp(f, 0.0, 1.0);
  float g = 1.0 - f;
  return NodeClosure(g * a.color + f * b.color, g * a.roughness + f * b.roughness,
                     g * a.metallic + f * b.metallic, g * a.specular + f * b.specular,
                     g * a.weight + f * b.weight, g * a.alpha + f * b.alpha,
                     g * a.emission + f * b.emission, g * a.normal + f * b.normal);
}

NodeClosure node_add_shader(NodeClosure a, NodeClosure b)
{
  return NodeClosure(a.color + b.color, a.roughness + b.roughness, a.metallic + b.metallic,
                     a.specular + b.specular, a.weight + b.weight, a.alpha + b.alpha,
                     a.emission + b.emission, a.normal + b.normal);
}

vec3 node_finite3(vec3 v, float limit)
{
  return vec3(isnan(v.x) ? 0.0 : clamp(v.x, -limit, limit), isnan(v.y) ? 0.0 : clamp(v.y, -limit, limit),
              isnan(v.z) ? 0.0 : clamp(v.z, -limit, limit));
}

/* The sums back as parameters (a surface with no reflecting part: black, rough, no specular). */
void node_closure_resolve(NodeClosure c, inout vec4 base, inout float roughness, inout float metallic,
                          inout float specular, inout float alpha, inout vec3 emission, inout vec3 normal)
{
  float nl = length(c.normal);
  normal = (nl > 1e-12 && !isinf(nl)) ? c.normal / nl : normal;
  float coverage = clamp(c.alpha, 0.0, 1.0);
  float inv = (coverage > 1e-6) ? 1.0 / coverage : 0.0;
  float winv = (c.weight > 1e-6) ? 1.0 / c.weight : 0.0;
  base = vec4(c.color * inv, 1.0);
  specular = c.specular * inv;
  emission = c.emission * inv;
  roughness = (c.weight > 1e-6) ? c.roughness * winv : 1.0;
  metallic = c.metallic * winv;
  alpha = coverage;
  /* NaN or infinite inputs (a division the tree did, an absurd constant) draw finite. */
  base = vec4(node_finite3(base.rgb, 1e6), 1.0);
  specular = node_finite3(vec3(specular), 1e6).x;
  emission = node_finite3(emission, 1e20);
  roughness = node_finite3(vec3(roughness), 1.0).x;
  metallic = node_finite3(vec3(metallic), 1.0).x;
  alpha = node_finite3(vec3(alpha), 1.0).x;
}

#endif
