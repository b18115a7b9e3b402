"""Materials and the world as Penumbra draws them, read from Blender's node trees.

A Principled BSDF is read through Blender's own ``PrincipledBSDFWrapper`` (the reader its
importers and exporters use): base colour, roughness, metallic, IOR, specular level and tint, alpha,
emission colour and strength, and the normal map, each as a value or an image texture with
its UV map and Mapping node. Besides what the wrapper follows, an input may come from a
Color Attribute / Attribute node (vertex colours), an RGB or Value node, or through reroutes.
Emission and Diffuse BSDF surfaces are read directly.

Anything else is compiled (``nodetree``: the tree as generated GLSL, ``Material.tree``)
where that draws more than this reader; what neither reads falls back to the material's
viewport display values (or the input's own value), and the material carries a message
that says so: the engine reports it once per render and the Material panel shows it.
Nothing is dropped silently.

No gpu here: the result is plain data (``Material``, ``TextureRef``) the renderer turns
into shader variants and uniforms.
"""

import math
from dataclasses import dataclass, field

import numpy as np

from . import volumes
from .sockets import source as _source

# Channels a texture can drive, in the order of the shader's texture slots.
CHANNELS = ("base_color", "roughness", "metallic", "alpha", "emission", "normal")
LUMINANCE = np.array([0.2126, 0.7152, 0.0722])  # Rec.709: Blender's colour -> value conversion
INTERPOLATION = {"Closest": 0, "Linear": 1, "Cubic": 1, "Smart": 1}
EXTENSION = {"REPEAT": 0, "EXTEND": 1, "CLIP": 2, "MIRROR": 3}
BLEND_MODES = ("OPAQUE", "HASHED", "BLEND")


@dataclass(frozen=True)
class TextureRef:
    """One image texture feeding one channel."""

    image: str  # image datablock name (the GPU texture cache key)
    uv_map: str = ""  # "" = the mesh's active render UV map
    output: str = "Color"  # the Image Texture socket used: "Color" or "Alpha"
    interpolation: str = "Linear"
    extension: str = "REPEAT"
    transform: tuple = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0))  # uv' = M @ (u, v, 1) (Mapping node)
    component: int = 0  # a value channel: 0 the colour's luminance (or alpha), 1-3 R, G, B (Separate Color)


@dataclass
class Material:
    base_color: tuple = (0.8, 0.8, 0.8, 1.0)
    roughness: float = 0.5
    specular: float = 0.5  # Specular IOR Level
    ior: float = 1.5
    specular_tint: tuple = (1.0, 1.0, 1.0)
    metallic: float = 0.0
    alpha: float = 1.0
    # Principled Transmission Weight (a Glass BSDF: 1): the share of the dielectric's diffuse
    # that is light refracted from behind instead (features/refraction.py).
    transmission: float = 0.0
    thickness_mode: str = "SPHERE"  # Settings > Thickness Mode (EEVEE's): how light leaves it again
    emission: tuple = (0.0, 0.0, 0.0)  # colour * strength
    normal_strength: float = 0.0  # 0: no normal map
    textures: dict = field(default_factory=dict)  # channel -> TextureRef
    color_attribute: str | None = None  # base colour from this colour attribute ("" = active)
    blend: str = "OPAQUE"  # OPAQUE, HASHED (dithered alpha) or BLEND (sorted, blended)
    cull_camera: bool = False  # Settings › Backface Culling › Camera: back faces not drawn
    cull_shadow: bool = False  # Settings › Backface Culling › Shadow: back faces cast no shadow
    holdout: bool = False  # a Holdout shader: a hole in the film where it shows (it still casts)
    transparent_shadow: bool = True  # Settings > Transparent Shadows: off, alpha casts as opaque
    messages: tuple = ()  # what could not be read, for the render report and the panel
    tree: object = None  # nodetree.CompiledTree: the node tree drawn as generated GLSL
    name: str = ""  # the material's name (its Cryptomatte id)
    pass_index: int = 0  # Material > Settings > Pass Index (the Material Index pass)
    # Its Volume output (``volumes.Medium``): the object's interior is that medium; None: none.
    volume: object = None
    # False: nothing is linked to its Surface output while its Volume output is (as in Cycles,
    # the surface is not drawn: light crosses it).
    surface: bool = True

    @property
    def f0(self):
        """The dielectric's reflectance at normal incidence (``dielectric_f0``)."""
        return dielectric_f0(self.ior, self.specular, self.specular_tint)

    @property
    def uv_maps(self):
        """UV maps the material's textures read ("" = the active render map)."""
        maps = {t.uv_map for t in self.textures.values()}
        if self.tree is not None and "UV" in self.tree.needs:
            maps.add(self.tree.uv_map)
        return tuple(sorted(maps))

    @property
    def transmits(self):
        """Whether light from behind shows through it (its transmission, on a dielectric)."""
        return self.tree is None and not self.holdout and self.transmission > 0.0 and self.metallic < 1.0

    @property
    def subsurface(self):
        """Whether a share of its diffuse scatters below the surface (``features/subsurface.py``)."""
        return self.tree is not None and self.tree.sss and not self.holdout

    @property
    def uses_alpha(self):
        transparent = self.tree is not None and self.tree.transparent
        return self.blend != "OPAQUE" and (self.alpha < 1.0 or "alpha" in self.textures or transparent)

    @property
    def features(self):
        """What the shader variant of this material samples (frozenset of names)."""
        out = {f"TEX_{c.upper()}" for c in self.textures}
        if self.color_attribute is not None:
            out.add("VCOL")
        if self.uses_alpha:
            out.add(f"ALPHA_{self.blend}")
        if self.holdout:
            out.add("HOLDOUT")
        if self.transmits:
            out.add("TRANSMISSION")
            if self.thickness_mode == "SLAB":
                out.add("THICKNESS_SLAB")
        if self.tree is not None:
            out.add(f"NODES_{self.tree.key}")
            if "UV" in self.tree.needs:
                out.add("TREE_UV")
            if self.tree.normal:
                out.add("TREE_NORMAL")
            if self.tree.lobes == 2:
                out.add("TREE_LOBES")
            if self.tree.coat:
                out.add("TREE_COAT")
            if self.tree.film:
                out.add("TREE_FILM")
            if self.tree.sheen:
                out.add("TREE_SHEEN")
            if self.tree.aniso:
                out.add("TREE_ANISO")
            if self.tree.sss:
                out.add("TREE_SSS")
        return frozenset(out)


def dielectric_f0(ior, level, tint=(1.0, 1.0, 1.0)):
    """The Principled BSDF's dielectric reflectance at normal incidence, as Blender's (Cycles'
    principled closure, EEVEE's principled GLSL): f0 = ((ior - 1) / (ior + 1))^2, times
    2 x Specular IOR Level, times Specular Tint, clamped to [0, 1] per channel -> (r, g, b,
    the untinted f0). The GLSL twin is ``node_principled_f0`` (shaders/nodes/shader.glsl)."""
    ior, level = _bounded(ior, 1.5), _bounded(level, 0.0)
    f0 = ((ior - 1.0) / (ior + 1.0)) ** 2 * 2.0 * level
    rgb = tuple(min(f0 * _bounded(t, 0.0), 1.0) for t in tuple(tint)[:3])
    return (*rgb, min(f0, 1.0))


def _bounded(value, nan):
    """``value`` in [0, 1e6] (``nan`` when NaN), as ``node_principled_f0`` bounds its inputs:
    no product of them is 0 x inf."""
    value = float(value)
    return nan if math.isnan(value) else min(max(value, 0.0), 1e6)


# --- reading ------------------------------------------------------------------------------


def _mapping_transform(mapping):
    """A Mapping node as a 2x3 affine map of (u, v, 1), or (transform, message)."""
    if mapping is None:
        return TextureRef.transform, None
    kind = mapping.vector_type
    loc = mapping.inputs["Location"].default_value if "Location" in mapping.inputs else (0, 0, 0)
    rot = mapping.inputs["Rotation"].default_value if "Rotation" in mapping.inputs else (0, 0, 0)
    scale = mapping.inputs["Scale"].default_value if "Scale" in mapping.inputs else (1, 1, 1)
    message = None
    linked = any(s.is_linked for s in mapping.inputs if s.name != "Vector")
    if linked or abs(rot[0]) > 1e-6 or abs(rot[1]) > 1e-6:
        message = "a Mapping node with linked inputs or X/Y rotation (only its 2-D part is used)"
    c, s = math.cos(rot[2]), math.sin(rot[2])
    rotation = np.array([[c, -s], [s, c]])
    scale2 = np.array([scale[0], scale[1]], dtype=np.float64)
    loc2 = np.array([loc[0], loc[1]], dtype=np.float64)
    if kind in {"POINT", "VECTOR"}:
        lin = rotation @ np.diag(scale2)
        off = loc2 if kind == "POINT" else np.zeros(2)
    elif kind == "TEXTURE":  # the inverse of POINT
        inv_scale = np.where(np.abs(scale2) > 1e-12, 1.0 / np.where(scale2 == 0, 1, scale2), 0.0)
        lin = np.diag(inv_scale) @ rotation.T
        off = -lin @ loc2
    else:  # NORMAL
        return TextureRef.transform, "a Mapping node of type Normal"
    return tuple(tuple(float(x) for x in row) for row in np.column_stack([lin, off])), message


def _image_ref(node, output, notes):
    """A TextureRef for Image Texture ``node`` read through its ``output`` socket."""
    image = node.image
    if image is None:
        return None
    uv_map = ""
    vector_node, vector_out = _source(node.inputs["Vector"])
    mapping = None
    if vector_node is not None and vector_node.bl_idname == "ShaderNodeMapping":
        mapping = vector_node
        vector_node, vector_out = _source(mapping.inputs["Vector"])
    if vector_node is not None:
        if vector_node.bl_idname == "ShaderNodeUVMap":
            uv_map = vector_node.uv_map
        elif vector_node.bl_idname == "ShaderNodeTexCoord" and vector_out.name == "UV":
            pass
        else:
            notes.append(f"texture coordinates from '{vector_node.name}' (UV is used)")
    if node.projection != "FLAT":
        notes.append(f"image projection {node.projection} (flat UV is used)")
    if node.interpolation in {"Cubic", "Smart"}:
        notes.append(f"{node.interpolation} interpolation (drawn as Linear)")
    transform, message = _mapping_transform(mapping)
    if message:
        notes.append(message)
    return TextureRef(
        image=image.name_full,
        uv_map=uv_map,
        output=output,
        interpolation=node.interpolation,
        extension=node.extension,
        transform=transform,
    )


def _input(socket, kind, notes, label):
    """What feeds input ``socket`` of a shader node: ('value', v) for its own value or an
    RGB/Value node, ('texture', TextureRef), ('attribute', name), or ('unsupported', value)
    after noting why. ``kind``: 'color' or 'value'."""
    node, out = _source(socket)
    if node is None:
        value = socket.default_value
        return "value", (tuple(value) if kind == "color" else float(value))
    idname = node.bl_idname
    if idname == "ShaderNodeTexImage":
        ref = _image_ref(node, out.name, notes)
        if ref is not None:
            return "texture", ref
        notes.append(f"{label}: an Image Texture node without an image")
        return "value", ((0.0, 0.0, 0.0, 1.0) if kind == "color" else 0.0)
    if idname in {"ShaderNodeSeparateColor", "ShaderNodeSeparateRGB"} and kind == "value":
        # One component of an image (glTF's packed occlusion/roughness/metallic maps).
        src, src_out = _source(node.inputs[0])
        rgb = getattr(node, "mode", "RGB") == "RGB"
        if rgb and src is not None and src.bl_idname == "ShaderNodeTexImage" and src_out.name == "Color":
            ref = _image_ref(src, "Color", notes)
            if ref is not None:
                return "texture", TextureRef(**{**ref.__dict__, "component": 1 + list(node.outputs).index(out)})
    if idname == "ShaderNodeVertexColor" and kind == "color":
        return "attribute", node.layer_name
    if idname == "ShaderNodeAttribute" and kind == "color" and node.attribute_type == "GEOMETRY":
        return "attribute", node.attribute_name
    if idname == "ShaderNodeRGB":
        value = out.default_value
        return "value", (tuple(value) if kind == "color" else float(np.dot(LUMINANCE, value[:3])))
    if idname == "ShaderNodeValue":
        v = float(out.default_value)
        return "value", ((v, v, v, 1.0) if kind == "color" else v)
    notes.append(f"{label} from a '{node.bl_label or idname}' node")
    return "unsupported", None


def _surface(mat):
    """The shader node the active Material Output's Surface socket draws, or None."""
    tree = getattr(mat, "node_tree", None)
    if tree is None:
        return None
    outputs = [n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputMaterial"]
    active = [n for n in outputs if n.is_active_output and n.target in {"ALL", "EEVEE"}] or outputs
    for out in active:
        node, _socket = _source(out.inputs["Surface"])
        if node is not None:
            return node
    return None


def _display(mat, notes, reason):
    """The material's viewport display values, used when its shader cannot be drawn."""
    notes.append(reason)
    return Material(
        base_color=tuple(mat.diffuse_color),
        roughness=float(mat.roughness),
        specular=float(getattr(mat, "specular_intensity", 0.5)),
        metallic=float(mat.metallic),
    )


def _blend_mode(mat):
    method = getattr(mat, "surface_render_method", None)
    if method == "BLENDED":
        return "BLEND"
    return "HASHED"  # DITHERED (EEVEE's default): alpha as coverage, converging over samples


def material_from_blender(mat):
    """A Blender material as Penumbra draws it (``Material``), with a message for every part
    it could not read, and its back-face culling settings (as EEVEE reads them)."""
    out = _material_surface(mat)
    if mat is not None:
        out.cull_camera = bool(getattr(mat, "use_backface_culling", False))
        out.cull_shadow = bool(getattr(mat, "use_backface_culling_shadow", False))
        out.transparent_shadow = bool(getattr(mat, "use_transparent_shadow", True))
        out.thickness_mode = str(getattr(mat, "thickness_mode", "SPHERE"))
        out.name = str(mat.name)
        out.pass_index = int(getattr(mat, "pass_index", 0))
    return out


def _material_surface(mat):
    if mat is None:
        return Material()
    notes = []
    if not getattr(mat, "use_nodes", True) or getattr(mat, "node_tree", None) is None:
        out = Material(
            base_color=tuple(mat.diffuse_color),
            roughness=float(mat.roughness),
            specular=float(getattr(mat, "specular_intensity", 0.5)),
            metallic=float(mat.metallic),
        )
        return out
    surface = _surface(mat)
    # Only a Volume output: no surface, the interior alone (as Cycles draws it).
    whole_volume = surface is None and _linked_outputs(
        mat.node_tree, "ShaderNodeOutputMaterial", "Volume", {"ALL", "EEVEE"}
    )
    out = _shader(mat, surface, notes)
    whole = out is None and not whole_volume
    if out is None:
        out = _display(mat, notes, "its surface shader is drawn with the viewport display colour")
    elif "alpha" in out.textures or out.alpha < 1.0:
        out.blend = _blend_mode(mat)
    if notes or _writes_aovs(mat):
        out, notes = _compiled(mat, out, notes, whole or _writes_aovs(mat))
    if _linked_outputs(mat.node_tree, "ShaderNodeOutputMaterial", "Displacement", {"ALL", "EEVEE"}):
        notes.append("its Displacement output is not drawn")
    medium = volumes.medium_of(mat.node_tree, "ShaderNodeOutputMaterial", "", {"ALL", "EEVEE"})
    if medium is not None:
        notes.extend(medium.messages)
        out.volume = None if medium.empty else medium
        out.surface = not whole_volume
    if out.transmits and _linked_outputs(mat.node_tree, "ShaderNodeOutputMaterial", "Thickness", {"ALL", "EEVEE"}):
        notes.append("its Thickness output is not read (the object's smallest dimension is its thickness)")
    out.messages = tuple(f"material '{mat.name}': {n}" for n in dict.fromkeys(notes))
    return out


def _writes_aovs(mat):
    """Whether ``mat``'s tree has an AOV Output node (only its compiled tree writes them)."""
    return any(n.bl_idname == "ShaderNodeOutputAOV" and not n.mute for n in mat.node_tree.nodes)


def _compiled(mat, read, notes, whole):
    """The material drawn through its compiled node tree (``nodetree``) where that draws more
    than the reader above: it compiled every input, or fewer inputs fell back than the reader
    could not read, or the reader fell back for the whole surface. Materials the reader takes
    whole keep its path (its image channels, shadow cut-outs and tests). -> (Material, notes)."""
    from . import nodetree

    tree, message = nodetree.compile_material(mat)
    if tree is None or tree.surface_fallback:
        return read, notes + ([message] if message else [])
    unread = sum(1 for n in notes if " from a '" in n or n.endswith("' shader"))
    if not (tree.fallbacks == 0 or whole or tree.fallbacks < unread):
        return read, notes
    out = Material(tree=tree)
    if tree.transparent:
        out.blend = _blend_mode(mat)
    if "VCOL" in tree.needs:
        out.color_attribute = tree.color_attribute
    new_notes = list(tree.messages)
    principled = [n for n in mat.node_tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled"]
    if len(principled) == 1 and not tree.normal:
        _normal_map(None, principled[0], new_notes, out)
        normal = out.textures.get("normal")
        # Both named and different (one unnamed may be the same layer: the object decides,
        # extract.Needs.of).
        if normal is not None and "UV" in tree.needs and normal.uv_map and tree.uv_map and normal.uv_map != tree.uv_map:
            new_notes.append("a normal map on another UV map than the tree's (the tree's map is used)")
    return out, new_notes


def _black():
    """What an unlinked shader socket gives: no light at all."""
    return Material(base_color=(0.0, 0.0, 0.0, 1.0), specular=0.0, roughness=1.0)


def _shader(mat, node, notes, depth=0):
    """The Material of shader ``node`` (None: not understood; ``notes`` says why)."""
    if node is None:
        return _black()
    idname = node.bl_idname
    if idname == "ShaderNodeBsdfPrincipled":
        return _principled(mat, node, notes)
    if idname == "ShaderNodeEmission":
        return _emission_shader(node, notes)
    if idname == "ShaderNodeBsdfDiffuse":
        return _diffuse_shader(node, notes)
    if idname in {"ShaderNodeBsdfGlass", "ShaderNodeBsdfRefraction"}:
        return _glass_shader(node, notes, reflects=idname == "ShaderNodeBsdfGlass")
    if idname in {"ShaderNodeBsdfHair", "ShaderNodeBsdfHairPrincipled"}:
        return _hair_shader(mat, node, notes)
    if idname in {"ShaderNodeBsdfGlossy", "ShaderNodeBsdfAnisotropic"}:
        out = Material(metallic=1.0)
        out.base_color = _color_channel(node.inputs["Color"], notes, "Color", out, "base_color", (0.8, 0.8, 0.8, 1.0))
        out.roughness = _value_channel(node.inputs["Roughness"], notes, "Roughness", out, "roughness", 0.5)
        _normal_map(None, node, notes, out)
        from .nodetree import anisotropy_unread

        notes += [f"{name} is not drawn" for name in anisotropy_unread(node)]  # the compiled tree draws it
        return out
    if idname == "ShaderNodeBsdfTransparent":
        out = _black()
        out.alpha = 0.0
        return out
    if idname == "ShaderNodeHoldout":
        out = _black()
        out.holdout = True
        return out
    if idname == "ShaderNodeMixShader" and depth < 8:
        return _mix_shader(mat, node, notes, depth)
    notes.append(f"'{node.bl_label or idname}' shader")
    return None


_MIXED = ("roughness", "specular", "metallic", "alpha", "normal_strength")  # and ior, tint: the reflecting side's


def _mix_shader(mat, node, notes, depth):
    """A Mix Shader with a constant factor of two shaders Penumbra reads: their values mixed
    (a Transparent BSDF mixed in gives alpha). Textured sides are not mixed: the side with
    the larger weight is drawn, with a message."""
    fac_in = node.inputs[0]
    if fac_in.is_linked:
        notes.append("a Mix Shader with a linked factor")
        return None
    fac = min(max(float(fac_in.default_value), 0.0), 1.0)
    sides = [_shader(mat, _source(node.inputs[i])[0], notes, depth + 1) for i in (1, 2)]
    if any(side is None for side in sides):
        return None
    a, b = sides
    if fac in (0.0, 1.0):
        return b if fac == 1.0 else a
    if a.alpha > 0.0 and b.alpha > 0.0 and not (a.holdout or b.holdout or _emits_only(a) or _emits_only(b)):
        notes.append("a Mix Shader of two surfaces (drawn as two lobes by the compiled node tree)")
        return None
    if a.holdout or b.holdout:
        notes.append("a Holdout shader mixed with another (the side with the larger factor is drawn)")
        return b if fac >= 0.5 else a
    if a.textures or b.textures or a.color_attribute is not None or b.color_attribute is not None:
        notes.append("a Mix Shader of textured shaders (the side with the larger factor is drawn)")
        return b if fac >= 0.5 else a
    out = Material()
    # A transparent side contributes no surface: the mix's surface values are the other side's.
    wa, wb = (1.0 - fac) * a.alpha, fac * b.alpha
    total = wa + wb
    ta = wa / total if total > 0.0 else 0.5
    for name in _MIXED:
        setattr(out, name, ta * getattr(a, name) + (1.0 - ta) * getattr(b, name))
    # The level is mixed (f0 scales with it); IOR and tint are the more reflecting side's.
    reflecting = a if ta * a.specular >= (1.0 - ta) * b.specular else b
    out.ior, out.specular_tint = reflecting.ior, reflecting.specular_tint
    # Keep the mixed diffuse albedo (what the eye reads as the colour): base * (1 - metallic).
    albedo = ta * np.array(a.base_color[:3]) * (1.0 - a.metallic) + (1.0 - ta) * np.array(b.base_color[:3]) * (
        1.0 - b.metallic
    )
    if out.metallic < 0.999:
        base = albedo / (1.0 - out.metallic)
    else:
        base = ta * np.array(a.base_color[:3]) + (1.0 - ta) * np.array(b.base_color[:3])
    out.base_color = (*(float(c) for c in base), 1.0)
    out.alpha = total
    out.emission = tuple((1.0 - fac) * x + fac * y for x, y in zip(a.emission, b.emission, strict=True))
    return out


def _emits_only(m):
    """A shader read with no reflecting surface (an Emission, an unlinked socket)."""
    return not m.textures and m.specular == 0.0 and m.metallic == 0.0 and max(m.base_color[:3]) == 0.0


def _fed_and_constant(a, b, constant_node):
    """Of two inputs, (the one a node feeds, the other's constant value: its own, or that of a
    ``constant_node`` (RGB / Value) feeding it); None unless exactly that."""
    for fed, constant in ((a, b), (b, a)):
        src, src_out = _source(constant)
        if src is None:
            value = constant.default_value
        elif src.bl_idname == constant_node:
            value = src_out.default_value
        else:
            continue
        return (fed, value) if _source(fed)[0] is not None else None
    return None


def _multiplied(socket):
    """A Mix (Color) node set to Multiply with a constant factor, one side fed by something
    and the other a constant colour: (the socket that feeds, per-channel tint) such that the
    node gives that input x tint (mix(A, A B, f) = A (1 - f + f B)); else None."""
    node, out = _source(socket)
    if node is None:
        return None
    if node.bl_idname == "ShaderNodeMix" and node.data_type == "RGBA" and out.identifier == "Result_Color":
        sockets = {s.identifier: s for s in node.inputs}
        fac, a, b, clamp = sockets["Factor_Float"], sockets["A_Color"], sockets["B_Color"], node.clamp_result
    elif node.bl_idname == "ShaderNodeMixRGB":
        fac, a, b, clamp = node.inputs[0], node.inputs["Color1"], node.inputs["Color2"], node.use_clamp
    else:
        return None
    if node.blend_type != "MULTIPLY" or fac.is_linked:
        return None
    found = _fed_and_constant(a, b, "ShaderNodeRGB")
    if found is None:
        return None
    f = min(max(float(fac.default_value), 0.0), 1.0)
    tint = tuple(1.0 - f + f * float(c) for c in found[1][:3])
    return None if clamp and max(tint) > 1.0 else (found[0], (*tint, 1.0))


def _color_channel(socket, notes, label, out, channel, fallback):
    """A colour input: its value, or a texture / colour attribute (then the multiplier the
    shader applies to it: 1, or a Multiply node's constant tint)."""
    multiplied = _multiplied(socket)
    source, tint = multiplied if multiplied is not None else (socket, (1.0, 1.0, 1.0, 1.0))
    kind, value = _input(source, "color", notes, label)
    if kind == "texture":
        out.textures[channel] = value
        return tint
    if kind == "attribute":
        out.color_attribute = value
        return tint
    if kind == "unsupported":
        return fallback
    return tuple(float(v) * t for v, t in zip(value, tint, strict=False))


def _scaled(socket):
    """A Math node set to Multiply with one input a constant (its own value or a Value node)
    and the other fed: (the fed socket, the constant); else None. Clamped products are read
    only while the constant is at most 1 (then nothing in [0, 1] reaches the clamp)."""
    node, _out = _source(socket)
    if node is None or node.bl_idname != "ShaderNodeMath" or node.operation != "MULTIPLY":
        return None
    found = _fed_and_constant(node.inputs[0], node.inputs[1], "ShaderNodeValue")
    if found is None or (node.use_clamp and not 0.0 <= float(found[1]) <= 1.0):
        return None
    return found[0], float(found[1])


def _value_channel(socket, notes, label, out, channel, fallback):
    """A value input: its value, or a texture (then the multiplier the shader applies to it: 1,
    or a Math Multiply node's constant)."""
    scaled = _scaled(socket) if channel is not None else None
    source, factor = scaled if scaled is not None else (socket, 1.0)
    kind, value = _input(source, "value", notes, label)
    if kind == "texture" and channel is None:
        notes.append(f"a texture into {label} (its value is used)")
        return float(socket.default_value)
    if kind == "texture":
        out.textures[channel] = value
        return factor
    if kind in {"unsupported", "attribute"}:
        return fallback
    return float(value) * factor


def _principled(mat, node, notes):
    from bpy_extras.node_shader_utils import PrincipledBSDFWrapper

    wrapper = PrincipledBSDFWrapper(mat, is_readonly=True)
    if wrapper.node_principled_bsdf != node:
        wrapper = None  # another Principled node is wired elsewhere: read the drawn one directly
    out = Material()
    inputs = node.inputs
    display = tuple(mat.diffuse_color)
    out.base_color = _color_channel(inputs["Base Color"], notes, "Base Color", out, "base_color", display)
    out.roughness = _value_channel(inputs["Roughness"], notes, "Roughness", out, "roughness", float(mat.roughness))
    out.metallic = _value_channel(inputs["Metallic"], notes, "Metallic", out, "metallic", float(mat.metallic))
    spec_name = "Specular IOR Level" if "Specular IOR Level" in inputs else "Specular"
    out.specular = _value_channel(inputs[spec_name], notes, spec_name, out, None, 0.5)
    if "IOR" in inputs:
        out.ior = _value_channel(inputs["IOR"], notes, "IOR", out, None, 1.5)
    tint = inputs.get("Specular Tint")
    if tint is not None and hasattr(tint.default_value, "__len__"):  # a colour since Blender 4.0
        if _source(tint)[0] is not None:
            notes.append("a linked Specular Tint (its own value is used)")
        out.specular_tint = tuple(float(v) for v in tint.default_value[:3])
    alpha = _value_channel(inputs["Alpha"], notes, "Alpha", out, "alpha", 1.0)
    out.alpha = alpha
    emit_name = "Emission Color" if "Emission Color" in inputs else "Emission"
    emission = _color_channel(inputs[emit_name], notes, "Emission Color", out, "emission", (0.0, 0.0, 0.0, 1.0))
    strength_in = inputs.get("Emission Strength")
    strength = 1.0 if strength_in is None else _value_channel(strength_in, notes, "Emission Strength", out, None, 1.0)
    out.emission = tuple(float(c) * strength for c in emission[:3])
    if "emission" in out.textures and strength == 0.0:
        del out.textures["emission"]
    _normal_map(wrapper, node, notes, out)
    if "alpha" in out.textures or alpha < 1.0:
        out.blend = "HASHED"  # the material's render method decides (material_from_blender)
    from .nodetree import principled_unread

    unread = principled_unread(node)
    for name in ("Transmission Weight", "Transmission"):
        sock = inputs.get(name)
        if name in unread and not sock.is_linked:  # a constant: drawn (features/refraction.py)
            out.transmission = min(max(float(sock.default_value), 0.0), 1.0)
            unread.remove(name)
    notes += [f"{name} is not drawn" for name in unread]
    return out


def _normal_map(wrapper, node, notes, out):
    normal_node, _ = _source(node.inputs["Normal"])
    if normal_node is None:
        return
    if normal_node.bl_idname != "ShaderNodeNormalMap":
        notes.append(f"Normal from a '{normal_node.bl_label}' node (not drawn)")
        return
    if normal_node.space != "TANGENT":
        notes.append(f"{normal_node.space.lower()}-space normal maps (only tangent space is drawn)")
        return
    strength_in = normal_node.inputs["Strength"]
    strength = float(wrapper.normalmap_strength if wrapper is not None else strength_in.default_value)
    kind, value = _input(normal_node.inputs["Color"], "color", notes, "Normal Map color")
    if kind != "texture" or strength == 0.0:
        return
    ref = value
    if normal_node.uv_map:
        ref = TextureRef(**{**ref.__dict__, "uv_map": normal_node.uv_map})
    out.textures["normal"] = ref
    out.normal_strength = strength


def _emission_shader(node, notes):
    out = Material(base_color=(0.0, 0.0, 0.0, 1.0), specular=0.0, roughness=1.0)
    color = _color_channel(node.inputs["Color"], notes, "Emission Color", out, "emission", (1.0, 1.0, 1.0, 1.0))
    strength = _value_channel(node.inputs["Strength"], notes, "Emission Strength", out, None, 1.0)
    out.emission = tuple(float(c) * strength for c in color[:3])
    if out.color_attribute is not None:
        notes.append("a colour attribute into Emission (not drawn)")
        out.color_attribute = None
    return out


def _glass_shader(node, notes, reflects=True):
    """A Glass BSDF: a dielectric of its IOR that transmits all it does not reflect, its colour
    tinting both (as Cycles' glass); a Refraction BSDF (``reflects`` False) the same without
    the reflection (Specular IOR Level 0: all of it transmits)."""
    out = Material(transmission=1.0, specular=0.5 if reflects else 0.0)
    out.base_color = _color_channel(node.inputs["Color"], notes, "Color", out, "base_color", (1.0, 1.0, 1.0, 1.0))
    out.roughness = _value_channel(node.inputs["Roughness"], notes, "Roughness", out, "roughness", 0.0)
    out.ior = _value_channel(node.inputs["IOR"], notes, "IOR", out, None, 1.45)
    if "base_color" not in out.textures:
        out.specular_tint = tuple(float(c) for c in out.base_color[:3])
    distribution = getattr(node, "distribution", "GGX")
    rough = out.roughness > 0.0 or "roughness" in out.textures
    if rough and distribution not in {"GGX", "MULTI_GGX", "SHARP"}:  # (all alike at roughness 0)
        notes.append(f"a {node.bl_label}'s {distribution.title()} distribution (drawn as GGX)")
    _normal_map(None, node, notes, out)
    return out


def _diffuse_shader(node, notes):
    out = Material(specular=0.0, roughness=1.0)
    out.base_color = _color_channel(node.inputs["Color"], notes, "Color", out, "base_color", (0.8, 0.8, 0.8, 1.0))
    _normal_map(None, node, notes, out)  # a Bump, ...: named, so the compiled tree draws it
    return out


def _hair_shader(mat, node, notes):
    """A Hair BSDF, or a Principled Hair BSDF given by its colour: a diffuse surface of that
    colour (no hair lobes; named). A Principled Hair BSDF by melanin or absorption takes the
    viewport display colour."""
    if getattr(node, "parametrization", "COLOR") != "COLOR":
        return _display(
            mat, notes, f"'{node.name}' (hair, by {node.parametrization.lower()}): the viewport display colour"
        )
    notes.append(f"'{node.name}' (hair BSDF) is drawn as a diffuse surface of its colour")
    out = Material(specular=0.0, roughness=1.0)
    out.base_color = _color_channel(node.inputs["Color"], notes, "Color", out, "base_color", (0.8, 0.8, 0.8, 1.0))
    return out


def summary(read):
    """What the Material panel shows of a read ``Material``: (icon, text) lines, the messages
    last (the same words as the render report, without the material's name)."""
    textures = ", ".join(c.replace("_", " ") for c in read.textures) or "none"
    lines = [("TEXTURE", f"Textures: {textures}")]
    if read.tree is not None:
        lines.insert(0, ("NODETREE", f"Node tree: compiled to GLSL ({len(read.tree.constants)} constants)"))
    if read.color_attribute is not None:
        lines.append(("GROUP_VCOL", f"Colour attribute: {read.color_attribute or 'the active one'}"))
    alpha = {"OPAQUE": "opaque", "HASHED": "dithered (hashed over samples)", "BLEND": "blended"}[read.blend]
    if read.holdout:
        alpha = "holdout (a hole in the film)"
    lines.append(("IMAGE_ALPHA", f"Alpha: {alpha}"))
    if read.transmits:
        mode = "a slab" if read.thickness_mode == "SLAB" else "a sphere"
        lines.append(("MATERIAL", f"Transmission: {read.transmission:.2f}, through {mode} (Thickness Mode)"))
    if read.tree is not None and read.tree.coat:
        lines.append(("MATERIAL", "Coat: a GGX layer over the surface"))
    if read.tree is not None and read.tree.sheen:
        lines.append(("MATERIAL", "Sheen: microfiber, over the surface and under any coat"))
    if read.tree is not None and read.tree.aniso:
        lines.append(("MATERIAL", "Anisotropic: GGX stretched along the tangent"))
    if read.tree is not None and read.tree.sss:
        lines.append(("MATERIAL", "Subsurface: Burley diffusion over the screen"))
    if read.volume is not None:
        v = read.volume
        where = "its interior (the object's bounding box)" if read.surface else "its interior alone (no surface)"
        lines.append(
            (
                "OUTLINER_DATA_VOLUME",
                f"Volume: {where}; extinction {float(v.extinction.mean()):.3g}, "
                f"scattering {float(v.scatter.mean()):.3g} per unit, anisotropy {v.anisotropy:.2f}",
            )
        )
    lines += [("ERROR", m.split(": ", 1)[-1]) for m in read.messages]
    return lines


# --- world --------------------------------------------------------------------------------


@dataclass(frozen=True)
class WorldSun:
    """World > Settings > Sun, as EEVEE reads it: the Environment Texture's radiance above
    ``threshold`` becomes a sun of angle ``angle`` (radians), shadowed when ``shadow``, the
    rest stays in the world's SH light (``frame/world/sun.py``). A threshold of 0 extracts none."""

    threshold: float = 10.0
    angle: float = 0.0092
    shadow: bool = True

    @classmethod
    def of(cls, world):
        threshold = float(getattr(world, "sun_threshold", 0.0))
        if not (threshold > 0.0 and np.isfinite(threshold)):
            return None
        return cls(threshold, float(getattr(world, "sun_angle", 0.0092)), bool(getattr(world, "use_sun_shadow", True)))


@dataclass
class World:
    """Light from the world: ``sh`` are order-2 spherical-harmonic coefficients (9, 3) of its
    radiance (a constant world has only the first), ``background`` the colour the film shows
    where nothing is drawn. An Environment Texture's world has both None until the renderer
    projects them from the image's GPU texture (``frame/world/sh_light.py``)."""

    sh: np.ndarray
    background: np.ndarray
    messages: tuple = ()
    image: str | None = None  # an Environment Texture image drawn behind the scene
    strength: float = 1.0  # its Background strength
    env: np.ndarray | None = None  # the image box-filtered to at most 128 x 64, times strength (world_light)
    # The Environment Texture's Mapping rotation: world direction -> the image's direction (3, 3),
    # None for none.
    rotation: np.ndarray | None = None
    sun: WorldSun | None = None  # World > Settings > Sun (EEVEE's): its light above a threshold
    lightgroup: str = ""  # World > Settings > Light Group: the light group its light is in
    # Where the sun took the image's light above its threshold: that threshold (radiance, with
    # the strength), what the rest of the world's light is clamped to; None where it took none.
    sun_clamp: float | None = None
    # World > Volume (``volumes.Medium``): a medium filling the view to the clip end; None: none.
    volume: object = None

    @property
    def mean(self):
        """The mean radiance (black until an Environment Texture's light is projected)."""
        return self.sh[0] * SH_C0 if self.sh is not None else np.zeros(3)

    @classmethod
    def constant(cls, color, messages=()):
        color = np.asarray(color, dtype=np.float64)[:3]
        sh = np.zeros((9, 3))
        sh[0] = color / SH_C0
        return cls(sh=sh, background=color.copy(), messages=tuple(messages))


SH_C0 = 0.28209479177387814  # Y_0^0


def sh_basis(d):
    """The nine real SH basis functions at unit directions ``d`` (..., 3) -> (..., 9)."""
    x, y, z = d[..., 0], d[..., 1], d[..., 2]
    return np.stack(
        [
            np.full_like(x, SH_C0),
            0.4886025119029199 * y,
            0.4886025119029199 * z,
            0.4886025119029199 * x,
            1.0925484305920792 * x * y,
            1.0925484305920792 * y * z,
            0.31539156525252005 * (3.0 * z * z - 1.0),
            1.0925484305920792 * x * z,
            0.5462742152960396 * (x * x - y * y),
        ],
        axis=-1,
    )


def equirect_sh(rgb, rotation=None):
    """SH coefficients (9, 3) of an equirectangular radiance image ``rgb`` (h, w, 3), row 0
    at the bottom (Blender's pixel order), as Blender maps it: u = 0.5 - atan2(y, x) / 2pi,
    v = atan2(z, hypot(x, y)) / pi + 0.5. ``rotation`` (3, 3): world direction -> the
    image's (an Environment Texture's Mapping); the SH are of the world's directions."""
    h, w = rgb.shape[:2]
    v = (np.arange(h) + 0.5) / h
    u = (np.arange(w) + 0.5) / w
    lat = (v - 0.5) * math.pi  # elevation
    lon = (0.5 - u) * 2.0 * math.pi  # atan2(y, x)
    cl = np.cos(lat)[:, None]
    d = np.stack(
        [np.cos(lon)[None, :] * cl, np.sin(lon)[None, :] * cl, np.broadcast_to(np.sin(lat)[:, None], (h, w))],
        axis=-1,
    )
    solid_angle = (2.0 * math.pi / w) * (math.pi / h) * np.broadcast_to(cl, (h, w))
    if rotation is not None:
        d = d @ np.asarray(rotation, np.float64)  # the image's direction -> the world's (R^T d)
    basis = sh_basis(d)  # (h, w, 9)
    return np.einsum("hwk,hwc,hw->kc", basis, rgb.astype(np.float64), solid_angle)


def _linked_outputs(tree, idname, socket, targets=None):
    """Whether the active output node(s) of type ``idname`` in ``tree`` have ``socket`` linked."""
    outputs = [n for n in tree.nodes if n.bl_idname == idname]
    active = [n for n in outputs if n.is_active_output and (targets is None or n.target in targets)] or outputs
    return any(socket in out.inputs and _source(out.inputs[socket])[0] is not None for out in active)


def _environment_rotation(world, env, messages):
    """The rotation (3, 3, world direction -> the image's) an Environment Texture ``env`` reads
    its image with: a Mapping node's Rotation on its Vector (Point, Vector and Normal rotate the
    direction, Texture by the inverse); None without one. What else feeds the vector (a
    Mapping's Location or Scale, another node) is named in ``messages``."""
    socket = env.inputs.get("Vector") if hasattr(env.inputs, "get") else None
    node, _ = _source(socket) if socket is not None else (None, None)
    if node is None:
        return None
    if node.bl_idname != "ShaderNodeMapping":
        if node.bl_idname != "ShaderNodeTexCoord":
            messages.append(
                f"world '{world.name}': the Environment Texture's Vector from '{node.bl_label}' is not drawn"
            )
        return None
    from mathutils import Euler

    rotation = node.inputs["Rotation"]
    if rotation.is_linked or any(node.inputs[k].is_linked for k in ("Location", "Scale") if k in node.inputs):
        messages.append(f"world '{world.name}': a linked input of the Mapping node is not drawn (its value is used)")
    kind = node.vector_type
    if (
        kind == "POINT"
        and "Location" in node.inputs
        and any(abs(v) > 0.0 for v in node.inputs["Location"].default_value)
    ):
        messages.append(f"world '{world.name}': the Mapping node's Location is not drawn (only its Rotation)")
    if (
        kind != "NORMAL"
        and "Scale" in node.inputs
        and any(abs(v - 1.0) > 0.0 for v in node.inputs["Scale"].default_value)
    ):
        messages.append(f"world '{world.name}': the Mapping node's Scale is not drawn (only its Rotation)")
    m = np.array(Euler(tuple(rotation.default_value), "XYZ").to_matrix(), np.float64)
    if not np.all(np.isfinite(m)):
        return None
    return m.T if kind == "TEXTURE" else m


def world_from_blender(scene, world=None):
    """The scene world's light (``World``, see ``_world_surface``), or ``world``'s (a view
    layer's World Override), with its Volume shader's medium (``World.volume``)."""
    world = scene.world if world is None else world
    out = _world_surface(world)
    out.lightgroup = str(getattr(world, "lightgroup", "") or "") if world is not None else ""
    tree = getattr(world, "node_tree", None) if world is not None else None
    if tree is not None and getattr(world, "use_nodes", True):
        label = f"world '{world.name}': "
        medium = volumes.medium_of(tree, "ShaderNodeOutputWorld", label)
        if medium is not None:
            out.messages = (*out.messages, *medium.messages)
            out.volume = None if medium.empty else medium.placed("WORLD", np.eye(4), world.name)
    return out


def _world_surface(world):
    """The scene world's light (``World``): a Background shader's colour x strength, or an
    Environment Texture image's radiance as SH; anything else its colour with a message."""
    if world is None:
        return World.constant((0.0, 0.0, 0.0))
    tree = getattr(world, "node_tree", None)
    if tree is None or not getattr(world, "use_nodes", True):
        return World.constant(world.color)
    outputs = [n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputWorld"]
    active = [n for n in outputs if n.is_active_output] or outputs
    node = None
    for out in active:
        node, _ = _source(out.inputs["Surface"])
        if node is not None:
            break
    if node is None:
        return World.constant((0.0, 0.0, 0.0))
    if node.bl_idname != "ShaderNodeBackground":
        return World.constant(
            world.color, (f"world '{world.name}': '{node.bl_label}' shader (the world's viewport colour is used)",)
        )
    strength_in = node.inputs["Strength"]
    strength = float(strength_in.default_value)
    messages = []
    if strength_in.is_linked:
        messages.append(f"world '{world.name}': a linked Strength (its value is used)")
    src, out = _source(node.inputs["Color"])
    if src is None:
        return World.constant(np.array(node.inputs["Color"].default_value[:3]) * strength, messages)
    if src.bl_idname == "ShaderNodeTexEnvironment" and src.image is not None and all(src.image.size):
        if src.projection != "EQUIRECTANGULAR":
            messages.append(f"world '{world.name}': {src.projection} projection (read as equirectangular)")
        rotation = _environment_rotation(world, src, messages)
        # Its light (sh) is projected from the image's GPU texture by the renderer
        # (frame/world/sh_light.py): no pixel is read here.
        return World(
            sh=None,
            background=None,
            messages=tuple(messages),
            image=src.image.name_full,
            strength=strength,
            rotation=rotation,
            sun=WorldSun.of(world),
        )
    if src.bl_idname == "ShaderNodeRGB":
        return World.constant(np.array(out.default_value[:3]) * strength, messages)
    messages.append(f"world '{world.name}': Color from a '{src.bl_label}' node (the world's viewport colour is used)")
    return World.constant(np.array(world.color[:3]) * strength, messages)
