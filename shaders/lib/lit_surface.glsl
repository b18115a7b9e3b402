// requires: lib/material.glsl lib/sheen.glsl lib/anisotropy.glsl
#ifndef PENUMBRA_LIB_LIT_SURFACE
#define PENUMBRA_LIB_LIT_SURFACE

/* Blender's light passes, one a lit variant (LIGHT_PASS; 0: the whole colour), each the
 * light of one kind of lobe without the surface's emission (engine/frame/features/passes.py). */
#define LIGHT_PASS_DIFFUSE 1          /* lights' and world's light on the diffuse lobes */
#define LIGHT_PASS_DIFFUSE_INDIRECT 2 /* the diffuse bounce (INDIRECT_RSM) */
#define LIGHT_PASS_GLOSSY 3           /* lights' and world's light on the specular lobes */
#define LIGHT_PASS_GLOSSY_INDIRECT 4  /* what the specular lobes' traced rays met of the scene */
#define LIGHT_PASS_TRANSMISSION 5     /* what a transmissive surface shows through it */
#define LIGHT_PASS_GROUP 6            /* a light group: its lights (light_mask), its objects' emission
                                       * (group_emission) and the world's light if it is in the group
                                       * (LIGHT_GROUP_WORLD) */
#define LIGHT_PASS_SUBSURFACE 7       /* the light on the diffuse share below the surface, lights',
                                       * world's and bounce (features/subsurface.py) */

/* The surface the lit pass shades (lit.frag.glsl): its point, the view, its geometric normals,
 * and its lobes. A material is one lobe. A compiled node tree whose Mix / Add Shader joins two
 * surfaces (engine/scene/nodetree.py) is NODE_LOBES == 2: each lobe its own Principled
 * parameters and shading normal, weighted per pixel (shaders/nodes/shader.glsl). Each light's
 * shadow is looked up once, then every lobe's BSDF under it (lit_lights.glsl add_light); the
 * world lights every lobe; the colour is the lobes' light summed by their weights. The Shadow
 * pass weights each light by the heavier lobe's cosine, the Normal pass writes the heavier
 * lobe's normal. */

#ifndef NODE_LOBES
#  define NODE_LOBES 1
#endif
#ifndef NODE_PROCEDURAL
#  define NODE_PROCEDURAL 0 /* a compiled node tree with procedural textures (programs.with_tree) */
#endif

/* One lobe's shading values (lit_bsdf.glsl lobe_setup). */
struct Lobe {
  vec3 N;      /* shading normal, on the viewer's side */
  vec3 albedo; /* diffuse, with the specular layer's energy taken out */
  vec4 f0;     /* rgb: reflectance at normal incidence, a: at grazing (Schlick's f90) */
  float shininess;
  float alpha;  /* GGX roughness (Principled roughness squared, at least 0.002) */
  float rough;  /* the Principled roughness (what blurs the world's specular) */
  float weight; /* the lobe's share of the surface (1 for a single lobe) */
  float ms;     /* the specular's multiple-scattering gain (lit_bsdf.glsl ggx_ms_gain) */
#if NODE_ANISO
  vec3 T, B;       /* its tangent frame (lib/anisotropy.glsl lobe_anisotropy) */
  float ax, ay;    /* GGX roughness along T and B */
#endif
#if NODE_FILM
  float film;      /* the Thin Film's share of its dielectric specular (lib/thin_film.glsl) */
  float metal;     /* its metallic, whose Fresnel the film leaves */
  vec3 metal_f0;   /* the metal's reflectance at normal incidence (the base colour) */
  vec3 film_dfg;   /* the film's reflectance towards the viewer x the lobe's albedo at F = 1 */
  vec3 metal_film_dfg; /* the same of the film on the metal */
  vec3 film_tint;  /* Specular Tint, which the film's reflectance is multiplied by */
#endif
};

#ifndef NODE_COAT
#  define NODE_COAT 0
#endif
#ifndef NODE_FILM
#  define NODE_FILM 0
#endif
#ifndef NODE_SSS
#  define NODE_SSS 0 /* a share of the diffuse scatters below the surface (lib/subsurface.glsl) */
#endif
#ifndef SUBSURFACE
#  define SUBSURFACE 0 /* 1: the lit pass leaves that share to features/subsurface.py */
#endif

/* A Principled BSDF's coat (NODE_COAT; lit_bsdf.glsl coat_setup): a dielectric GGX layer over
 * every lobe. ``below``: what reaches the lobes under it and back (1 - weight x the coat's
 * directional albedo towards the viewer, times its tint over the path through it). */
struct Coat {
  vec3 N;
  float weight;
  float alpha; /* GGX roughness (Coat Roughness squared, at least 0.002) */
  float rough;
  float f0;    /* ((IOR - 1) / (IOR + 1))^2 */
  vec3 below;
  vec2 ab;     /* its environment BRDF towards the viewer (env_brdf) */
  float ms;    /* its multiple-scattering gain (ggx_ms_gain) */
};

struct Surface {
  vec3 P, V;
  vec3 Ng; /* the interpolated mesh normal, before any normal map: what shadow biases follow */
  vec3 Nf; /* the drawn facet's normal (the plane the shadow map holds), on Ng's side */
  vec3 Nv; /* the drawn facet's normal on the side it is seen from */
#if TERMINATOR_OFFSET
  vec3 smooth_offset; /* from the flat triangle to the smooth surface (world) */
#endif
  Lobe lobe[NODE_LOBES];
#if NODE_COAT
  Coat coat;
#endif
#if NODE_SHEEN
  Sheen sheen; /* over the lobes, under the coat (lib/sheen.glsl) */
#endif
};

#define NO_SHADOW -1

/* The lobe the Shadow and Normal passes follow: the heavier one. */
int heavier_lobe(Surface s)
{
#if NODE_LOBES == 2
  return (s.lobe[1].weight > s.lobe[0].weight) ? 1 : 0;
#else
  return 0;
#endif
}

/* The surface's point, view and geometric normals at this fragment. Returns the interpolated
 * normal (the face's where it is degenerate: a zero-scale or broken mesh), turned across a hair
 * strip (HAIR_STRIP), before any normal map. */
vec3 surface_geometry(out Surface s)
{
  s.P = v_world;
  vec3 N = v_normal;
  float nlen = length(N);
  if (!(nlen > 1e-20)) {
    N = cross(dFdx(s.P), dFdy(s.P));
    nlen = length(N);
  }
  N = (nlen > 1e-30) ? N / nlen : vec3(0.0, 0.0, 1.0);
#if HAIR_STRIP
  {
    /* Hair shaded as a cylinder, as EEVEE does: the normal turns from the camera (the strip's
     * centre) to the binormal (its edges); a pixel-wide strand (hair_pixel > 0) takes a random
     * point across it in each sample (EEVEE's random cosine distribution). */
    float cos_theta = clamp(v_hair.w, -1.0, 1.0);
    if (hair_pixel > 0.0) {
      cos_theta = 2.0 * fract(pixel_hash(gl_FragCoord.xy + 17.0) + frame.alpha_offset) - 1.0;
    }
    float sin_theta = sqrt(max(0.0, 1.0 - cos_theta * cos_theta));
    vec3 B = v_hair.xyz;
    float bl = length(B);
    N = normalize(N * sin_theta + ((bl > 1e-20) ? B / bl : vec3(0.0)) * cos_theta + 1e-30);
  }
#endif
  s.V = (frame.is_ortho != 0) ? -frame.camera_forward : normalize(frame.camera_position - s.P);
  s.Ng = (dot(N, s.V) < 0.0) ? -N : N;
  /* Derivatives within the pixel quad come from this triangle: its plane. */
  vec3 f = cross(dFdx(s.P), dFdy(s.P));
  float fl = length(f);
  s.Nf = (fl > 1e-30) ? f / fl : s.Ng;
  s.Nv = (dot(s.Nf, s.V) < 0.0) ? -s.Nf : s.Nf;
  s.Nf = (dot(s.Nf, s.Ng) < 0.0) ? -s.Nf : s.Nf;
  return N;
}

/* The shading normal from the interpolated one ``N``: the node tree's (``tree_normal``, a Bump
 * and the like, NODE_NORMAL) or the material's tangent-space normal map (TEX_NORMAL, Blender's
 * Normal Map node: MikkTSpace tangent and sign from the mesh, or a frame from screen-space
 * derivatives of the UVs where it has none); on the viewer's side (two-sided, as Blender draws
 * meshes). */
vec3 shading_normal(vec3 N, vec3 tree_normal, Surface s)
{
#if NODE_NORMAL
  N = (dot(tree_normal, tree_normal) > 0.0) ? normalize(tree_normal) : N;
#endif
#if TEX_NORMAL
  vec3 mapped = SAMPLE_COLOR(normal, v_uv).rgb * 2.0 - 1.0;
  vec3 T = v_tangent.xyz;
  float sign_b = v_tangent.w;
  if (sign_b == 0.0 || !(dot(T, T) > 1e-20)) {
    vec3 dp1 = dFdx(s.P), dp2 = dFdy(s.P);
    vec2 du1 = dFdx(v_uv), du2 = dFdy(v_uv);
    vec3 dp2perp = cross(dp2, N), dp1perp = cross(N, dp1);
    T = dp2perp * du1.x + dp1perp * du2.x;
    vec3 B = dp2perp * du1.y + dp1perp * du2.y;
    sign_b = (dot(cross(N, T), B) < 0.0) ? -1.0 : 1.0;
  }
  T = T - N * dot(N, T);
  float tl = length(T);
  if (tl > 1e-20) {
    T /= tl;
    vec3 B = sign_b * cross(N, T);
    vec3 perturbed = normalize(T * mapped.x + B * mapped.y + N * mapped.z);
    N = normalize(mix(N, perturbed, max(material.normal_strength, 0.0)));
  }
#endif
  return (dot(N, s.V) < 0.0) ? -N : N;
}

#endif /* PENUMBRA_LIB_LIT_SURFACE */
