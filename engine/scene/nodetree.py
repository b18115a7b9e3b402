"""A material's shader node tree compiled to one GLSL function.

``compile_material(mat)`` walks back from the active Material Output's Surface socket and
writes the tree as GLSL statements, one temporary per node output, each a call of a node
function of our own (``shaders/nodes/<family>.glsl``, every one with a numpy twin in
``devkit/node_reference.py``). The result (``CompiledTree``) is plain data: the code of

    void node_tree(vec3 N, vec3 V, bool front, inout vec4 base, inout float roughness,
                   inout float metallic, inout vec4 specular, inout float alpha,
                   inout vec3 emission, inout vec3 normal)

which the lit pass calls where it reads the material (``shaders/lit.frag.glsl``, under
``NODE_TREE``; ``normal`` only where a shader's Normal input is compiled, a Bump say:
``NODE_NORMAL``), the GLSL families it needs, the surface data it reads (UV map, colour
attribute, texture space, world origin), its image textures, and its **constants**.

Constants are not in the code: every unlinked socket value and every plain number of a node
(a Value or RGB node, a Color Ramp's stops) is a row of the material's ``node_constants``
uniform block, so two trees that differ only in values give the same code and share one
program. The program key (``CompiledTree.key``) is a hash of the code and what it reads;
node names never reach the code. Enum properties (a Math operation, a blend mode, an
interpolation) are structure: compiled in as literals.

How Blender's rules are followed:
- node groups are inlined (nested; a group input left unlinked reads its value on the group
  node), reroutes followed, a muted link reads the socket's own value, a muted node passes
  its first input of the matching type through (``Node.internal_links``), else gives 0;
- implicit conversions as Blender's: colour to value is Rec.709 luminance, vector to value
  the mean of its components, a value to a colour is grey, a colour into a shader socket
  emits it;
- Mix Shader and Add Shader combine shaders per pixel with their factor, which may come from
  any node, as a weighted set of lobes (``shaders/nodes/shader.glsl``): each lobe a full set
  of Principled parameters with its own normal, shaded separately and summed by weight (Add:
  both weight 1, so energy can exceed 1, as in Blender). Penumbra shades at most two lobes
  per pixel; where more would result (nested mixes) the two most similar merge, per pixel,
  into one with their weighted parameters. Every closure ``Value`` says how many lobes it can
  hold (``Value.lobes``); a tree whose surface can hold two (``CompiledTree.lobes``) also
  defines ``node_tree_closure`` for the lit pass (``NODE_LOBES == 2``), and trees of one lobe
  (a shader alone, mixed with Emission or Transparent) compile the code and program they
  did before.

What cannot compile (an unknown node, a Script node, Light Path, an output Penumbra has no
data for) falls back for the shader input it feeds only: that input takes the value the
earlier reader (``materials.py``) would use (the viewport display colour, roughness and
metallic for the Principled BSDF's inputs; the socket's own value otherwise), and the
material's messages name the node once. A group that contains itself, a group node without
its group, a tree deeper than ``MAX_DEPTH`` links or larger than ``MAX_NODES`` node outputs,
more than ``MAX_CONSTANTS`` constants: a message, never a crash.

Adding a node is one registry entry: a function decorated ``@node("ShaderNodeX", family)``
that takes (compiler, node, output socket, context) and returns a ``Value`` (GLSL expression,
type), reading its inputs with ``c.input(node, name, ctx, type)`` (constants become uniforms
by themselves) and naming its ``family`` file under ``shaders/nodes/`` (e.g. ``texture_noise``
for a ``shaders/nodes/texture_noise.glsl``); a family's file names the families it calls on its
``// requires:`` line, and the shader loader includes them before it (``resolve_libs``).
Procedural textures read their coordinates with ``c.texture_vector(node, ctx)`` (Generated when
unlinked, as Blender does) and call the per-dimension entry points (``node_tex_noise_at``,
``node_tex_voronoi_at``): the all-dimension functions compile several times slower.
"""

import hashlib
from dataclasses import dataclass

import numpy as np

MAX_CONSTANTS = 1024  # vec4 rows of node_constants (16 KiB: the smallest uniform block GL allows)
MAX_NODES = 1500  # node outputs compiled (after inlining groups)
MAX_DEPTH = 120  # links followed from the output to the farthest node
MAX_GROUP_DEPTH = 16  # node groups inside node groups
MAX_IMAGES = 8  # image textures one tree samples
CURVE_SAMPLES = 128  # points an RGB Curves / Float Curve curve is tabulated at

GLSL_TYPES = {"float": "float", "vec2": "vec2", "vec3": "vec3", "vec4": "vec4", "closure": "NodeClosure"}
SOCKET_TYPES = {"VALUE": "float", "INT": "float", "BOOLEAN": "float", "VECTOR": "vec3", "RGBA": "vec4"}
SOCKET_TYPES["SHADER"] = "closure"

# Literal codes of the enums compiled into the GLSL (the switch cases of shaders/nodes/*.glsl).
MATH_OPS = (
    "ADD SUBTRACT MULTIPLY DIVIDE MULTIPLY_ADD POWER LOGARITHM SQRT INVERSE_SQRT ABSOLUTE EXPONENT "
    "MINIMUM MAXIMUM LESS_THAN GREATER_THAN SIGN COMPARE SMOOTH_MIN SMOOTH_MAX ROUND FLOOR CEIL TRUNC "
    "FRACT MODULO FLOORED_MODULO WRAP SNAP PINGPONG SINE COSINE TANGENT ARCSINE ARCCOSINE ARCTANGENT "
    "ARCTAN2 SINH COSH TANH RADIANS DEGREES"
).split()
VECTOR_MATH_OPS = (
    "ADD SUBTRACT MULTIPLY DIVIDE MULTIPLY_ADD CROSS_PRODUCT PROJECT REFLECT REFRACT FACEFORWARD "
    "DOT_PRODUCT DISTANCE LENGTH SCALE NORMALIZE ABSOLUTE POWER SIGN MINIMUM MAXIMUM FLOOR CEIL "
    "FRACTION MODULO WRAP SNAP SINE COSINE TANGENT"
).split()
VECTOR_MATH_VALUE = {"DOT_PRODUCT", "DISTANCE", "LENGTH"}  # the operations whose output is the Value
BLEND_MODES = (
    "MIX DARKEN MULTIPLY BURN LIGHTEN SCREEN DODGE ADD OVERLAY SOFT_LIGHT LINEAR_LIGHT DIFFERENCE "
    "EXCLUSION SUBTRACT DIVIDE HUE SATURATION VALUE COLOR"
).split()
MAP_RANGE_TYPES = ("LINEAR", "STEPPED", "SMOOTHSTEP", "SMOOTHERSTEP")
CLAMP_TYPES = ("MINMAX", "RANGE")
RAMP_INTERPOLATIONS = ("CONSTANT", "LINEAR", "EASE", "CARDINAL", "B_SPLINE")
RAMP_MODES = ("RGB", "HSV", "HSL")
RAMP_HUE = ("NEAR", "FAR", "CW", "CCW")
COLOR_MODES = ("RGB", "HSV", "HSL")
MAPPING_TYPES = ("POINT", "TEXTURE", "VECTOR", "NORMAL")
GRADIENT_TYPES = ("LINEAR", "QUADRATIC", "EASING", "DIAGONAL", "SPHERICAL", "QUADRATIC_SPHERE", "RADIAL")
NOISE_TYPES = ("FBM", "MULTIFRACTAL", "HYBRID_MULTIFRACTAL", "RIDGED_MULTIFRACTAL", "HETERO_TERRAIN")
VORONOI_FEATURES = ("F1", "F2", "SMOOTH_F1", "DISTANCE_TO_EDGE", "N_SPHERE_RADIUS")
VORONOI_METRICS = ("EUCLIDEAN", "MANHATTAN", "CHEBYCHEV", "MINKOWSKI")
WAVE_TYPES = ("BANDS", "RINGS")
WAVE_BANDS = ("X", "Y", "Z", "DIAGONAL")
WAVE_RINGS = ("X", "Y", "Z", "SPHERICAL")
WAVE_PROFILES = ("SIN", "SAW", "TRI")
IMAGE_INTERPOLATION = {"Closest": 0, "Linear": 1, "Cubic": 1, "Smart": 1}
IMAGE_EXTENSION = {"REPEAT": 0, "EXTEND": 1, "CLIP": 2, "MIRROR": 3}


class Fallback(Exception):
    """This input cannot be compiled: ``str(self)`` says which node and why."""


class TreeTooLarge(Exception):
    """The whole tree is beyond the compiler's bounds."""


@dataclass(frozen=True)
class Value:
    expr: str
    type: str  # float, vec3, vec4 or closure
    lobes: int = 0  # a closure: how many lobes it can hold (0, 1 or 2; shaders/nodes/shader.glsl)


@dataclass(frozen=True)
class NodeImage:
    """An image a compiled tree samples (sampler ``node_image_<index>``)."""

    image: str
    interpolation: str = "Linear"
    extension: str = "REPEAT"


@dataclass(frozen=True, eq=False)  # compared by identity (it holds an array)
class CompiledTree:
    key: str  # hash of the code and what it reads: equal trees share one program
    code: str  # the GLSL function node_tree(...)
    families: tuple  # shaders/nodes/*.glsl stems its nodes call, sorted (their needs: // requires:)
    constants: np.ndarray  # (n, 4) float32: the node_constants rows
    images: tuple  # NodeImage per sampler node_image_<i>
    needs: frozenset  # surface data read: UV, VCOL, GENERATED, ORIGIN, OBJECT_INFO, FRAME (the camera)
    uv_map: str = ""  # the UV map UV reads ("" = the active render map)
    color_attribute: str = ""  # the colour attribute VCOL reads ("" = the active one)
    transparent: bool = False  # alpha can be below 1
    messages: tuple = ()  # what fell back (without the material's name)
    fallbacks: int = 0  # shader inputs that fell back
    surface_fallback: bool = False  # the whole surface fell back (nothing compiled)
    normal: bool = False  # it computes the shading normal (a Bump, ...): NODE_NORMAL
    lobes: int = 1  # 2: a Mix / Add Shader of two surfaces, shaded as two lobes (NODE_LOBES == 2)
    aovs: tuple = ()  # the AOV names its AOV Output nodes write, in node_aovs' order (NODE_AOVS)
    coat: bool = False  # a Principled BSDF's coat is drawn (NODE_COAT; node_coat_keep)
    film: bool = False  # its Thin Film is drawn (NODE_FILM; node_film_keep)
    sheen: bool = False  # its Sheen is drawn (NODE_SHEEN; node_sheen_keep)
    aniso: bool = False  # an anisotropic lobe is drawn (NODE_ANISO; node_aniso_keep)
    sss: bool = False  # a share of its diffuse scatters below the surface (NODE_SSS; node_sss_keep)


# --- the registry -------------------------------------------------------------------------

NODES = {}  # bl_idname -> (function, family)


def node(*idnames, family=None):
    """Register a node compiler for ``idnames``; ``family``: its shaders/nodes file (stem)."""

    def register(fn):
        for idname in idnames:
            NODES[idname] = (fn, family)
        return fn

    return register


# --- the compiler -------------------------------------------------------------------------


@dataclass(frozen=True)
class Context:
    """Where in the tree evaluation is: the top-level tree, or inside a group node."""

    path: tuple = ()  # names of the group nodes entered
    group_node: object = None
    parent: object = None
    trees: tuple = ()  # node groups entered (a group inside itself is a broken file)


def _label(node):
    return node.bl_label or node.name or node.bl_idname


def _link(socket):
    """The link into ``socket`` Blender evaluates, or None (unlinked, muted or invalid)."""
    if not socket.is_linked:
        return None
    for link in socket.links:
        if getattr(link, "is_muted", False) or not getattr(link, "is_valid", True):
            return None
        return link
    return None


def _socket(sockets, key):
    """A socket by identifier, then name, then index."""
    if isinstance(key, int):
        return sockets[key]
    for s in sockets:
        if s.identifier == key:
            return s
    for s in sockets:
        if s.name == key and s.enabled:
            return s
    for s in sockets:
        if s.name == key:
            return s
    raise Fallback(f"no socket '{key}'")


_NORMAL_MAP = object()  # a normal input fed by a Normal Map node (``Compiler._vector_input``)


class Compiler:
    def __init__(self, mat):
        self.mat = mat
        self.lines = []
        self.constants = []
        self.cache = {}
        self.messages = []
        self.images = []
        self.needs = set()
        self.families = {"common", "shader"}
        self.uv_maps = []
        self.attributes = []
        self.depth = 0
        self.transparent = False
        self.fallbacks = 0
        self.surface_fallback = False
        self.normal = False
        self.coat = False  # a Principled BSDF's coat is drawn (NODE_COAT)
        self.film = False  # and its Thin Film (NODE_FILM)
        self.sheen = False  # and its Sheen (NODE_SHEEN)
        self.aniso = False  # an anisotropic lobe (NODE_ANISO)
        self.sss = False  # a subsurface share of the diffuse (NODE_SSS)

    # -- emitting --

    def temp(self, typ, expr, lobes=0):
        name = f"t{len(self.lines)}"
        self.lines.append(f"  {GLSL_TYPES[typ]} {name} = {expr};")
        if len(self.lines) > MAX_NODES:
            raise TreeTooLarge(f"more than {MAX_NODES} node outputs")
        return Value(name, typ, lobes)

    def const(self, value, typ):
        """A constant as a row of node_constants (never a literal in the code)."""
        if len(self.constants) >= MAX_CONSTANTS:
            raise TreeTooLarge(f"more than {MAX_CONSTANTS} constants")
        v = np.zeros(4, np.float64)
        if typ == "float":
            v[0] = float(value)
        else:
            seq = [float(x) for x in value]
            v[: min(len(seq), 4)] = seq[:4]
            if typ == "vec4" and len(seq) < 4:
                v[3] = 1.0
        v = np.nan_to_num(v, nan=0.0, posinf=3.0e38, neginf=-3.0e38)
        i = len(self.constants)
        self.constants.append(v)
        swizzle = {"float": ".x", "vec3": ".xyz", "vec4": ""}[typ]
        return Value(f"node_constants[{i}].v{swizzle}", typ)

    @staticmethod
    def zero(typ):
        return Value(
            {"float": "0.0", "vec3": "vec3(0.0)", "vec4": "vec4(0.0, 0.0, 0.0, 1.0)"}.get(typ, "node_closure_empty()"),
            typ,
        )

    def convert(self, v, typ):
        if v.type == typ:
            return v
        if typ == "closure":
            if v.type == "float":
                return Value(f"node_emission(vec4(vec3({v.expr}), 1.0), 1.0)", typ)
            return Value(f"node_emission({self.convert(v, 'vec4').expr}, 1.0)", typ)
        if v.type == "closure":
            raise Fallback("a shader linked into a value socket")
        table = {
            ("float", "vec3"): "vec3({})",
            ("float", "vec4"): "vec4(vec3({}), 1.0)",
            ("vec3", "float"): "node_vector_to_float({})",
            ("vec3", "vec4"): "vec4({}, 1.0)",
            ("vec4", "float"): "node_color_to_float({})",
            ("vec4", "vec3"): "({}).rgb",
        }
        return Value(table[(v.type, typ)].format(v.expr), typ)

    # -- reading sockets --

    def default(self, socket, typ):
        """An unlinked socket's own value, as a constant."""
        if not hasattr(socket, "default_value"):
            return self.zero(typ)
        value = socket.default_value
        own = SOCKET_TYPES.get(socket.type, "float")
        if own == "float":
            return self.convert(self.const(float(value), "float"), typ)
        if own == "closure":
            return self.zero(typ)
        return self.convert(self.const(tuple(value), own), typ)

    def input(self, node, key, ctx, typ):
        """Input ``key`` of ``node`` as a Value of GLSL type ``typ``."""
        return self.socket_value(_socket(node.inputs, key), ctx, typ)

    def linked(self, node, key):
        return _link(_socket(node.inputs, key)) is not None

    def socket_value(self, socket, ctx, typ):
        link = _link(socket)
        if link is None:
            return self.default(socket, typ)
        return self.convert(self.output(link.from_node, link.from_socket, ctx), typ)

    def output(self, node, socket, ctx):
        """What output ``socket`` of ``node`` gives (its own type)."""
        key = (ctx.path, node.name, socket.identifier)
        if key in self.cache:
            return self.cache[key]
        self.depth += 1
        try:
            if self.depth > MAX_DEPTH:
                raise TreeTooLarge(f"more than {MAX_DEPTH} nodes in a row")
            value = self._output(node, socket, ctx)
        finally:
            self.depth -= 1
        self.cache[key] = value
        return value

    def _output(self, node, socket, ctx):
        typ = SOCKET_TYPES.get(socket.type)
        idname = node.bl_idname
        if idname == "NodeReroute":
            link = _link(node.inputs[0])
            if link is None:
                return self.zero(typ or "float")
            return self.output(link.from_node, link.from_socket, ctx)
        if idname == "NodeGroupInput":
            return self._group_input(socket, ctx, typ)
        if typ is None:
            raise Fallback(f"a '{_label(node)}' node's {socket.name} output ({socket.type.lower()})")
        if node.mute:
            for link in node.internal_links:
                if link.to_socket.identifier == socket.identifier:
                    return self.socket_value(link.from_socket, ctx, typ)
            return self.zero(typ)
        if idname == "ShaderNodeGroup":
            return self._group(node, socket, ctx, typ)
        entry = NODES.get(idname)
        if entry is None:
            raise Fallback(f"a '{_label(node)}' node")
        fn, family = entry
        if family:
            self.families.add(family)
        try:
            value = fn(self, node, socket, ctx)
        except (Fallback, TreeTooLarge):
            raise
        except (AttributeError, KeyError, IndexError, TypeError, ValueError) as exc:
            raise Fallback(f"a '{_label(node)}' node ({exc})") from exc
        return self.convert(value, typ) if value.type != typ and typ != "closure" else value

    def _group_input(self, socket, ctx, typ):
        if ctx.group_node is None:
            return self.zero(typ or "float")
        outer = next((s for s in ctx.group_node.inputs if s.identifier == socket.identifier), None)
        if outer is None:
            return self.zero(typ or "float")
        return self.socket_value(outer, ctx.parent, typ or SOCKET_TYPES.get(outer.type, "float"))

    def _group(self, group, socket, ctx, typ):
        tree = group.node_tree
        if tree is None:
            raise Fallback(f"a group node '{group.name}' without its node group")
        if tree in ctx.trees:
            raise Fallback(f"node group '{tree.name}' contains itself")
        if len(ctx.trees) >= MAX_GROUP_DEPTH:
            raise Fallback(f"node groups nested more than {MAX_GROUP_DEPTH} deep")
        outputs = [n for n in tree.nodes if n.bl_idname == "NodeGroupOutput"]
        out = next((n for n in outputs if getattr(n, "is_active_output", False)), outputs[0] if outputs else None)
        if out is None:
            return self.zero(typ)
        inner = next((s for s in out.inputs if s.identifier == socket.identifier), None)
        if inner is None:
            return self.zero(typ)
        sub = Context(ctx.path + (group.name,), group, ctx, ctx.trees + (tree,))
        return self.socket_value(inner, sub, typ)

    # -- surface data --

    def uv(self, name=""):
        """The UV coordinates of map ``name`` ("" = the active render map) as a vec3."""
        if name not in self.uv_maps:
            self.uv_maps.append(name)
            if len(self.uv_maps) == 2:
                self.messages.append(f"a second UV map '{name}' (UV map '{self.uv_maps[0] or 'active'}' is used)")
        self.needs.add("UV")
        return Value("vec3(v_uv, 0.0)", "vec3")

    def attribute(self, name=""):
        """Colour attribute ``name`` ("" = the active one) as a vec4."""
        if name not in self.attributes:
            self.attributes.append(name)
            if len(self.attributes) == 2:
                self.messages.append(f"a second colour attribute '{name}' ('{self.attributes[0] or 'active'}' is used)")
        self.needs.add("VCOL")
        return Value("v_color", "vec4")

    def generated(self):
        self.needs.add("GENERATED")
        return Value("node_generated()", "vec3")

    def texture_vector(self, node, ctx, key="Vector"):
        """A texture node's coordinates: its Vector input, Generated where unlinked."""
        if self.linked(node, key):
            return self.input(node, key, ctx, "vec3")
        return self.generated()

    # -- shader inputs with their fallback --

    def shader_input(self, node, key, ctx, typ, fallback=None, label=None):
        """An input of a shader node; what cannot compile falls back to ``fallback`` (or the
        socket's own value) and is named."""
        socket = _socket(node.inputs, key)
        try:
            return self.socket_value(socket, ctx, typ)
        except Fallback as exc:
            self.fallbacks += 1
            self.messages.append(f"{label or socket.name} from {exc}")
            if typ == "closure":
                return self.display_closure()
            if fallback is not None:
                return self.const(fallback, typ) if typ != "float" else self.const(float(fallback), "float")
            return self.default(socket, typ)

    def coat_normal_input(self, node, ctx):
        """A Principled BSDF's Coat Normal: vec3(0.0) (the surface's own interpolated normal,
        as Blender's coat takes it) where unlinked, else the compiled vector; a Normal Map there
        is named and not drawn (the reader's normal-map path draws the base's only)."""
        value = self._vector_input(node, "Coat Normal", ctx, "vec3(0.0)")
        if value is _NORMAL_MAP:
            self.messages.append("a Normal Map on the Coat Normal (the coat takes the surface's normal)")
            return Value("vec3(0.0)", "vec3")
        return value

    def tangent_input(self, node, ctx):
        """A shader's Tangent input: Cycles' radial tangent about Z of the generated coordinates
        where unlinked (what Cycles links there), else the compiled vector."""
        socket = _socket(node.inputs, "Tangent")
        if socket is not None and _link(socket) is not None:
            return self.shader_input(node, "Tangent", ctx, "vec3")
        return Value(f"node_radial_tangent({self.generated().expr}, mat3(model), N, 2)", "vec3")

    def normal_input(self, node, ctx):
        """A shader's Normal input: N where unlinked or fed by a Normal Map (the reader's
        normal-map path draws that one), else the compiled vector (a Bump, ...)."""
        value = self._vector_input(node, "Normal", ctx, "N")
        if value is _NORMAL_MAP:
            return Value("N", "vec3")
        if value.expr != "N":
            self.normal = True
        return value

    def _vector_input(self, node, identifier, ctx, unlinked):
        """The normal input ``identifier`` of ``node``: ``unlinked`` (a GLSL expression) where
        nothing feeds it or it fell back to its socket's value, _NORMAL_MAP where a Normal Map
        node feeds it, else the compiled vector."""
        socket = next((s for s in node.inputs if s.identifier == identifier), None)
        link = _link(socket) if socket is not None else None
        if link is None:
            return Value(unlinked, "vec3")
        src = link.from_node
        while src.bl_idname == "NodeReroute" and _link(src.inputs[0]) is not None:
            src = _link(src.inputs[0]).from_node
        if src.bl_idname == "ShaderNodeNormalMap":
            return _NORMAL_MAP
        value = self.shader_input(node, identifier, ctx, "vec3")
        return Value(unlinked, "vec3") if value.expr.startswith("node_constants") else value

    def display_closure(self):
        """The material's viewport display values as a surface."""
        m = self.mat
        base = self.const(tuple(m.diffuse_color), "vec4")
        r = self.const(float(m.roughness), "float")
        metal = self.const(float(m.metallic), "float")
        spec = "vec4(0.04)"  # Specular IOR Level 0.5 at IOR 1.5
        return Value(f"node_principled({base.expr}, {metal.expr}, {r.expr}, {spec}, 1.0, vec3(0.0), N)", "closure", 1)

    # -- the whole tree --

    def compile(self, surface_socket, aov_nodes=()):
        v = self.shader_input_root(surface_socket)
        body = "\n".join(self.lines)
        aov_code, aovs = self.compile_aovs(aov_nodes)
        signature = (
            "void node_tree(vec3 N, vec3 V, bool front, inout vec4 base, inout float roughness,\n"
            "               inout float metallic, inout vec4 specular, inout float alpha, inout vec3 emission,\n"
            "               inout vec3 normal)\n"
        )
        keep = f"  node_coat_keep({v.expr});\n" if self.coat else ""
        keep += f"  node_film_keep({v.expr});\n" if self.film else ""
        keep += f"  node_sheen_keep({v.expr});\n" if self.sheen else ""
        keep += f"  node_aniso_keep({v.expr});\n" if self.aniso else ""
        keep += f"  node_sss_keep({v.expr});\n" if self.sss else ""
        if v.lobes < 2:
            code = _prelude(self.needs) + (
                f"{signature}{{\n{body}\n{keep}"
                f"  node_closure_resolve({v.expr}, base, roughness, metallic, specular, alpha, emission, normal);\n"
                "}\n"
            )
        else:
            # Two lobes: the closure itself for the lit pass (NODE_LOBES == 2), and node_tree
            # (the lobes summed) for the passes that read one set of parameters (shadow alpha).
            code = _prelude(self.needs) + (
                f"NodeClosure node_tree_closure(vec3 N, vec3 V, bool front)\n{{\n{body}\n  return {v.expr};\n}}\n"
                f"{signature}{{\n"
                "  node_closure_resolve(node_tree_closure(N, V, front), base, roughness, metallic, specular, alpha,\n"
                "                       emission, normal);\n"
                "}\n"
            )
        code += aov_code
        families = tuple(sorted(self.families))
        needs = frozenset(self.needs)
        images = tuple(self.images)
        modes = ",".join(f"{i.interpolation}/{i.extension}" for i in images)
        digest = hashlib.sha1(f"{code}|{families}|{sorted(needs)}|{modes}|{len(self.constants)}".encode()).hexdigest()
        constants = np.array(self.constants, np.float32).reshape(-1, 4)
        return CompiledTree(
            key=digest[:12],
            code=code,
            families=families,
            constants=constants,
            images=images,
            needs=needs,
            uv_map=self.uv_maps[0] if self.uv_maps else "",
            color_attribute=self.attributes[0] if self.attributes else "",
            transparent=self.transparent,
            messages=tuple(dict.fromkeys(self.messages)),
            fallbacks=self.fallbacks,
            surface_fallback=self.surface_fallback,
            normal=self.normal,
            lobes=max(1, v.lobes),
            aovs=aovs,
            coat=self.coat,
            film=self.film,
            sheen=self.sheen,
            aniso=self.aniso,
            sss=self.sss,
        )

    def compile_aovs(self, nodes):
        """The AOV Output nodes ``nodes`` as ``node_aovs(N, V, front, aov)``: per node, in
        order, its Color (rgb) and Value (a) into ``aov[k]`` (the Shader AOV passes, drawn
        apart: ``features/passes.py``). Returns (code, their AOV names); a node whose input
        cannot compile writes 0 there and is named."""
        if not nodes:
            return "", ()
        self.lines, self.cache = [], {}  # its own function: the surface's temporaries are not in scope
        writes = []
        for k, node in enumerate(nodes):
            try:
                color = self.input(node, "Color", Context(), "vec4")
                value = self.input(node, "Value", Context(), "float")
                writes.append(f"  aov[{k}] = vec4(({color.expr}).rgb, {value.expr});")
            except Fallback as exc:
                self.messages.append(f"AOV '{_aov_name(node)}' from {exc} (written as 0)")
        body = "\n".join(self.lines + writes)
        code = f"void node_aovs(vec3 N, vec3 V, bool front, inout vec4 aov[NODE_AOV_SLOTS])\n{{\n{body}\n}}\n"
        return code, tuple(_aov_name(n) for n in nodes)

    def shader_input_root(self, socket):
        ctx = Context()
        try:
            return self.socket_value(socket, ctx, "closure")
        except Fallback as exc:
            self.fallbacks += 1
            self.surface_fallback = True
            self.messages.append(f"the surface from {exc} (drawn with the viewport display colour)")
            return self.display_closure()


def _prelude(needs):
    """Surface data the node functions read, as GLSL (per-draw push constants where needed)."""
    out = [
        "vec3 node_true_normal(vec3 V)\n{\n  vec3 f = node_safe_normalize(cross(dFdx(v_world), dFdy(v_world)));\n"
        "  return (dot(f, V) < 0.0) ? -f : f;\n}\n",
    ]
    if "FRAME" in needs:  # the camera's matrices: the lit pass only
        out.append(
            "vec3 node_window()\n{\n  vec4 c = frame.view_proj * vec4(v_world, 1.0);\n"
            "  return (abs(c.w) > 1e-30) ? vec3(c.xy / c.w * 0.5 + 0.5, 0.0) : vec3(0.0);\n}\n"
        )
    if "GENERATED" in needs:
        out.append(
            "vec3 node_generated()\n{\n  vec3 p = (inverse(model) * vec4(v_world, 1.0)).xyz;\n"
            "  return p * node_texspace_scale + node_texspace_offset;\n}\n"
        )
    return "".join(out)


def _aov_name(node):
    """The AOV an AOV Output node writes (``aov_name``; ``name`` before Blender 4.0)."""
    return str(getattr(node, "aov_name", "") or "")


def compile_material(mat):
    """``CompiledTree`` of ``mat``'s surface, or (None, message) when the tree is beyond the
    compiler's bounds or has no surface: returns (tree, message)."""
    tree = getattr(mat, "node_tree", None)
    if tree is None:
        return None, None
    outputs = [n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputMaterial"]
    active = [n for n in outputs if n.is_active_output and n.target in {"ALL", "EEVEE"}] or outputs
    surface = next((o.inputs["Surface"] for o in active if _link(o.inputs["Surface"]) is not None), None)
    if surface is None:
        return None, None
    compiler = Compiler(mat)
    aov_nodes = [n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputAOV" and not n.mute and _aov_name(n)]
    try:
        return compiler.compile(surface, aov_nodes), None
    except TreeTooLarge as exc:
        return None, f"its node tree is too large to compile ({exc})"
    except RecursionError:
        return None, "its node tree is too large to compile (too deep)"


# --- shaders ------------------------------------------------------------------------------


def _first(node, *names):
    for n in names:
        for s in node.inputs:
            if s.name == n or s.identifier == n:
                return n
    return None


@node("ShaderNodeBsdfPrincipled")
def _principled(c, node, socket, ctx):
    m = c.mat
    base = c.shader_input(node, "Base Color", ctx, "vec4", tuple(m.diffuse_color))
    metal = c.shader_input(node, "Metallic", ctx, "float", float(m.metallic))
    rough = c.shader_input(node, "Roughness", ctx, "float", float(m.roughness))
    level = c.shader_input(node, _first(node, "Specular IOR Level", "Specular"), ctx, "float", 0.5)
    ior = c.shader_input(node, "IOR", ctx, "float", 1.5) if _first(node, "IOR") else Value("1.5", "float")
    tint_socket = _socket(node.inputs, "Specular Tint") if _first(node, "Specular Tint") else None
    if tint_socket is not None and hasattr(tint_socket.default_value, "__len__"):  # a colour since 4.0
        tint = c.shader_input(node, "Specular Tint", ctx, "vec4", (1.0, 1.0, 1.0, 1.0))
    else:
        tint = Value("vec4(1.0)", "vec4")
    spec = c.temp("vec4", f"node_principled_f0({ior.expr}, {level.expr}, {tint.expr})")
    alpha_socket = _socket(node.inputs, "Alpha")
    if _link(alpha_socket) is not None or float(alpha_socket.default_value) < 1.0:
        c.transparent = True
    alpha = c.shader_input(node, "Alpha", ctx, "float", 1.0)
    emit_name = _first(node, "Emission Color", "Emission")
    emission = c.shader_input(node, emit_name, ctx, "vec4", (0.0, 0.0, 0.0, 1.0), "Emission Color")
    strength = "1.0"
    if _first(node, "Emission Strength"):
        strength = c.shader_input(node, "Emission Strength", ctx, "float", 1.0).expr
    normal = c.normal_input(node, ctx)
    unread = principled_unread(node)
    expr = (
        f"node_principled({base.expr}, {metal.expr}, {rough.expr}, {spec.expr}, {alpha.expr}, "
        f"({emission.expr}).rgb * {strength}, {normal.expr})"
    )
    if "Coat Weight" in unread:  # linked or above 0: the coat over the surface (NODE_COAT)
        unread.remove("Coat Weight")
        weight = c.shader_input(node, "Coat Weight", ctx, "float", 0.0)
        coat_rough = c.shader_input(node, "Coat Roughness", ctx, "float", 0.03)
        coat_ior = c.shader_input(node, "Coat IOR", ctx, "float", 1.5)
        tint = c.shader_input(node, "Coat Tint", ctx, "vec4", (1.0, 1.0, 1.0, 1.0))
        coat_normal = c.coat_normal_input(node, ctx)
        expr = (
            f"node_principled_coat({expr}, {weight.expr}, {coat_rough.expr}, {coat_ior.expr}, {tint.expr}, "
            f"{coat_normal.expr})"
        )
        c.coat = True
    if "Sheen Weight" in unread:  # linked or above 0: the sheen over the surface (NODE_SHEEN)
        unread.remove("Sheen Weight")
        weight = c.shader_input(node, "Sheen Weight", ctx, "float", 0.0)
        sheen_rough = c.shader_input(node, "Sheen Roughness", ctx, "float", 0.5)
        sheen_tint = c.shader_input(node, "Sheen Tint", ctx, "vec4", (1.0, 1.0, 1.0, 1.0))
        expr = f"node_principled_sheen({expr}, {weight.expr}, {sheen_rough.expr}, {sheen_tint.expr})"
        c.sheen = True
    if "Anisotropic" in unread:  # linked or above 0: an anisotropic specular (NODE_ANISO)
        unread.remove("Anisotropic")
        amount = c.shader_input(node, "Anisotropic", ctx, "float", 0.0)
        rotation = c.shader_input(node, "Anisotropic Rotation", ctx, "float", 0.0)
        tangent = c.tangent_input(node, ctx)
        expr = f"node_principled_aniso({expr}, {amount.expr}, {rotation.expr}, {tangent.expr}, {normal.expr})"
        c.aniso = True
    if "Subsurface Weight" in unread:  # linked or above 0: a share of the diffuse below (NODE_SSS)
        unread.remove("Subsurface Weight")
        weight = c.shader_input(node, "Subsurface Weight", ctx, "float", 0.0)
        radius = c.shader_input(node, "Subsurface Radius", ctx, "vec3", (1.0, 0.2, 0.1))
        scale = c.shader_input(node, "Subsurface Scale", ctx, "float", 0.05)
        walk = "0.0" if getattr(node, "subsurface_method", "RANDOM_WALK") == "BURLEY" else "1.0"
        expr = f"node_principled_sss({expr}, {weight.expr}, {radius.expr}, {scale.expr}, {walk})"
        c.sss = True
        c.messages += subsurface_approximations(node, "Subsurface Anisotropy")
    if "Thin Film Thickness" in unread:  # linked or above 0: the film on its specular (NODE_FILM)
        unread.remove("Thin Film Thickness")
        thickness = c.shader_input(node, "Thin Film Thickness", ctx, "float", 0.0)
        film_ior = c.shader_input(node, "Thin Film IOR", ctx, "float", 1.33)
        expr = f"node_principled_film({expr}, {thickness.expr}, {film_ior.expr}, {ior.expr}, {level.expr})"
        c.film = True
    c.messages += [f"{name} is not drawn" for name in unread]
    return c.temp("closure", expr, 1)


@node("ShaderNodeEmission")
def _emission(c, node, socket, ctx):
    color = c.shader_input(node, "Color", ctx, "vec4", None, "Emission Color")
    strength = c.shader_input(node, "Strength", ctx, "float", None, "Emission Strength")
    return c.temp("closure", f"node_emission({color.expr}, {strength.expr})")


@node("ShaderNodeBsdfDiffuse")
def _diffuse(c, node, socket, ctx):
    color = c.shader_input(node, "Color", ctx, "vec4")
    return c.temp("closure", f"node_diffuse({color.expr}, {c.normal_input(node, ctx).expr})", 1)


@node("ShaderNodeBsdfGlossy", "ShaderNodeBsdfAnisotropic")
def _glossy(c, node, socket, ctx):
    color = c.shader_input(node, "Color", ctx, "vec4")
    rough = c.shader_input(node, "Roughness", ctx, "float")
    normal = c.normal_input(node, ctx)
    expr = f"node_principled({color.expr}, 1.0, {rough.expr}, vec4(0.04), 1.0, vec3(0.0), {normal.expr})"
    if anisotropy_unread(node):  # linked or not 0: anisotropic (NODE_ANISO)
        amount = c.shader_input(node, "Anisotropy", ctx, "float", 0.0)
        rotation = c.shader_input(node, "Rotation", ctx, "float", 0.0)
        tangent = c.tangent_input(node, ctx)
        expr = f"node_glossy_aniso({expr}, {amount.expr}, {rotation.expr}, {tangent.expr}, {normal.expr})"
        c.aniso = True
    return c.temp("closure", expr, 1)


@node("ShaderNodeTangent")
def _tangent(c, node, socket, ctx):
    axis = {"X": 0, "Y": 1, "Z": 2}.get(getattr(node, "axis", "Z"), 2)
    if getattr(node, "direction_type", "RADIAL") != "RADIAL":
        c.messages.append("a Tangent node's UV Map tangent (drawn as Radial about Z)")
        axis = 2
    return c.temp("vec3", f"node_radial_tangent({c.generated().expr}, mat3(model), N, {axis})")


@node("ShaderNodeBsdfSheen")
def _sheen(c, node, socket, ctx):
    color = c.shader_input(node, "Color", ctx, "vec4")
    rough = c.shader_input(node, "Roughness", ctx, "float")
    if getattr(node, "distribution", "MICROFIBER") != "MICROFIBER":
        c.messages.append("a Sheen BSDF's Ashikhmin distribution (drawn as Microfiber)")
    normal = node.inputs.get("Normal")
    if normal is not None and normal.is_linked:
        c.messages.append("a Sheen BSDF's Normal (it takes the surface's)")
    c.sheen = True
    return c.temp("closure", f"node_sheen_bsdf({color.expr}, {rough.expr})")


@node("ShaderNodeSubsurfaceScattering")
def _subsurface(c, node, socket, ctx):
    color = c.shader_input(node, "Color", ctx, "vec4")
    scale = c.shader_input(node, "Scale", ctx, "float")
    radius = c.shader_input(node, "Radius", ctx, "vec3")
    c.sss = True
    c.messages += subsurface_approximations(node, "Anisotropy")
    walk = "0.0" if getattr(node, "falloff", "RANDOM_WALK") == "BURLEY" else "1.0"
    normal = c.normal_input(node, ctx).expr
    expr = f"node_subsurface({color.expr}, {scale.expr}, {radius.expr}, {normal}, {walk})"
    return c.temp("closure", expr, 1)


def subsurface_approximations(node, anisotropy):
    """What a subsurface node sets that the screen-space diffusion (features/subsurface.py)
    does not draw: a scattering Anisotropy other than 0, the Random Walk (Skin) method's own
    look; named once."""
    out = []
    sock = node.inputs.get(anisotropy)
    if sock is not None and (sock.is_linked or abs(float(sock.default_value)) > 0.0):
        out.append(f"{anisotropy} (the diffusion is isotropic)")
    return out


@node("ShaderNodeBsdfTransparent")
def _transparent(c, node, socket, ctx):
    c.transparent = True
    return Value("node_transparent()", "closure")


def _combine(a, b):
    """How Mix / Add Shader combine closures of ``a.lobes`` and ``b.lobes`` lobes: (GLSL
    function suffix, lobes of the result). One lobe in all stays one (summed: ``_shader``);
    two single lobes become two (``_split``); more are merged per pixel down to two, the two
    most similar first (``_merge``): Penumbra shades at most two lobes per pixel."""
    if a.lobes == 0 or b.lobes == 0:
        return "_shader", a.lobes + b.lobes
    if a.lobes == 1 and b.lobes == 1:
        return "_split", 2
    return "_merge", 2


@node("ShaderNodeMixShader")
def _mix_shader(c, node, socket, ctx):
    fac = c.shader_input(node, 0, ctx, "float", None, "Mix Shader Fac")
    a = c.shader_input(node, 1, ctx, "closure")
    b = c.shader_input(node, 2, ctx, "closure")
    how, lobes = _combine(a, b)
    return c.temp("closure", f"node_mix{how}({fac.expr}, {a.expr}, {b.expr})", lobes)


@node("ShaderNodeAddShader")
def _add_shader(c, node, socket, ctx):
    a = c.shader_input(node, 0, ctx, "closure")
    b = c.shader_input(node, 1, ctx, "closure")
    how, lobes = _combine(a, b)
    return c.temp("closure", f"node_add{how}({a.expr}, {b.expr})", lobes)


# --- inputs -------------------------------------------------------------------------------


@node("ShaderNodeValue")
def _value(c, node, socket, ctx):
    return c.const(float(node.outputs[0].default_value), "float")


@node("ShaderNodeRGB")
def _rgb(c, node, socket, ctx):
    return c.const(tuple(node.outputs[0].default_value), "vec4")


@node("ShaderNodeTexCoord")
def _tex_coord(c, node, socket, ctx):
    out = socket.identifier
    if out == "Generated":
        return c.generated()
    if out == "Normal":
        return c.temp("vec3", "node_safe_normalize(transpose(mat3(model)) * N)")
    if out == "UV":
        return c.uv(getattr(node, "uv_map", "") or "") if hasattr(node, "uv_map") else c.uv("")
    if out == "Object":
        if getattr(node, "object", None) is not None:
            raise Fallback("a 'Texture Coordinate' node's Object output of another object")
        return c.temp("vec3", "(inverse(model) * vec4(v_world, 1.0)).xyz")
    if out == "Camera":
        c.needs.add("FRAME")
        return c.temp("vec3", "(frame.view * vec4(v_world, 1.0)).xyz * vec3(1.0, 1.0, -1.0)")
    if out == "Window":
        c.needs.add("FRAME")
        return c.temp("vec3", "node_window()")
    if out == "Reflection":
        return c.temp("vec3", "reflect(-V, N)")
    raise Fallback(f"a 'Texture Coordinate' node's {socket.name} output")


@node("ShaderNodeUVMap")
def _uv_map(c, node, socket, ctx):
    return c.uv(node.uv_map)


@node("ShaderNodeVertexColor")
def _vertex_color(c, node, socket, ctx):
    v = c.attribute(node.layer_name)
    return Value("v_color.a", "float") if socket.identifier == "Alpha" else v


@node("ShaderNodeAttribute")
def _attribute(c, node, socket, ctx):
    if node.attribute_type != "GEOMETRY":
        raise Fallback(f"an 'Attribute' node of type {node.attribute_type.lower()}")
    c.attribute(node.attribute_name)
    out = socket.identifier
    if out == "Color":
        return Value("vec4(v_color.rgb, 1.0)", "vec4")
    if out == "Vector":
        return Value("v_color.rgb", "vec3")
    if out == "Fac":
        return Value("((v_color.r + v_color.g + v_color.b) / 3.0)", "float")
    return Value("v_color.a", "float")


@node("ShaderNodeNewGeometry")
def _geometry(c, node, socket, ctx):
    out = socket.identifier
    if out == "Position":
        c.needs.add("ORIGIN")
        return Value("(v_world + node_origin)", "vec3")
    if out == "Normal":
        return Value("N", "vec3")
    if out == "True Normal":
        return c.temp("vec3", "node_true_normal(V)")
    if out == "Incoming":
        return Value("V", "vec3")
    if out == "Backfacing":
        return Value("(front ? 0.0 : 1.0)", "float")
    raise Fallback(f"a 'Geometry' node's {socket.name} output")


@node("ShaderNodeObjectInfo")
def _object_info(c, node, socket, ctx):
    if socket.identifier == "Location":
        c.needs.add("ORIGIN")
        return Value("(model[3].xyz + node_origin)", "vec3")
    if socket.identifier in {"Color", "Alpha", "Random"}:
        c.needs.add("OBJECT_INFO")
        return {
            "Color": Value("vec4(node_object_color.rgb, 1.0)", "vec4"),
            "Alpha": Value("node_object_color.a", "float"),
            "Random": Value("node_object_random", "float"),
        }[socket.identifier]
    raise Fallback(f"an 'Object Info' node's {socket.name} output")


@node("ShaderNodeFresnel", family="input")
def _fresnel(c, node, socket, ctx):
    ior = c.input(node, "IOR", ctx, "float")
    n = c.input(node, "Normal", ctx, "vec3") if c.linked(node, "Normal") else Value("N", "vec3")
    return c.temp("float", f"node_fresnel({ior.expr}, {n.expr}, V, front)")


@node("ShaderNodeLayerWeight", family="input")
def _layer_weight(c, node, socket, ctx):
    blend = c.input(node, "Blend", ctx, "float")
    n = c.input(node, "Normal", ctx, "vec3") if c.linked(node, "Normal") else Value("N", "vec3")
    lw = c.temp("vec3", f"vec3(node_layer_weight({blend.expr}, {n.expr}, V, front), 0.0)")
    return Value(f"{lw.expr}.{'x' if socket.identifier == 'Fresnel' else 'y'}", "float")


# --- converters ---------------------------------------------------------------------------


@node("ShaderNodeMath", family="math")
def _math(c, node, socket, ctx):
    op = MATH_OPS.index(node.operation)
    a, b, d = (c.input(node, i, ctx, "float") for i in range(3))
    v = c.temp("float", f"node_math({op}, {a.expr}, {b.expr}, {d.expr})")
    return c.temp("float", f"clamp({v.expr}, 0.0, 1.0)") if node.use_clamp else v


@node("ShaderNodeVectorMath", family="vector")
def _vector_math(c, node, socket, ctx):
    c.families.add("math")
    op = VECTOR_MATH_OPS.index(node.operation)
    a, b, d = (c.input(node, i, ctx, "vec3") for i in range(3))
    s = c.input(node, "Scale", ctx, "float")
    v = c.temp("vec3", "vec3(0.0)")
    f = c.temp("float", "0.0")
    c.lines.append(f"  node_vector_math({op}, {a.expr}, {b.expr}, {d.expr}, {s.expr}, {v.expr}, {f.expr});")
    return f if socket.identifier == "Value" else v


@node("ShaderNodeMix", family="color")
def _mix(c, node, socket, ctx):
    kind = node.data_type
    if kind == "FLOAT":
        fac = c.input(node, "Factor_Float", ctx, "float")
        if node.clamp_factor:
            fac = Value(f"clamp({fac.expr}, 0.0, 1.0)", "float")
        a, b = c.input(node, "A_Float", ctx, "float"), c.input(node, "B_Float", ctx, "float")
        return c.temp("float", f"mix({a.expr}, {b.expr}, {fac.expr})")
    if kind == "VECTOR":
        uniform = node.factor_mode == "UNIFORM"
        fac = c.input(node, "Factor_Float" if uniform else "Factor_Vector", ctx, "float" if uniform else "vec3")
        if node.clamp_factor:
            fac = Value(f"clamp({fac.expr}, 0.0, 1.0)", fac.type)
        a, b = c.input(node, "A_Vector", ctx, "vec3"), c.input(node, "B_Vector", ctx, "vec3")
        return c.temp("vec3", f"mix({a.expr}, {b.expr}, {fac.expr})")
    if kind == "RGBA":
        fac = c.input(node, "Factor_Float", ctx, "float")
        if node.clamp_factor:
            fac = Value(f"clamp({fac.expr}, 0.0, 1.0)", "float")
        a, b = c.input(node, "A_Color", ctx, "vec4"), c.input(node, "B_Color", ctx, "vec4")
        v = c.temp("vec4", f"node_mix_color({BLEND_MODES.index(node.blend_type)}, {fac.expr}, {a.expr}, {b.expr})")
        if node.clamp_result:
            v = c.temp("vec4", f"vec4(clamp({v.expr}.rgb, 0.0, 1.0), {v.expr}.a)")
        return v
    raise Fallback(f"a 'Mix' node of type {kind.lower()}")


@node("ShaderNodeMixRGB", family="color")
def _mix_rgb(c, node, socket, ctx):
    fac = c.input(node, "Fac", ctx, "float")
    a, b = c.input(node, "Color1", ctx, "vec4"), c.input(node, "Color2", ctx, "vec4")
    v = c.temp("vec4", f"node_mix_color({BLEND_MODES.index(node.blend_type)}, {fac.expr}, {a.expr}, {b.expr})")
    if node.use_clamp:
        v = c.temp("vec4", f"vec4(clamp({v.expr}.rgb, 0.0, 1.0), {v.expr}.a)")
    return v


@node("ShaderNodeMapRange", family="converter")
def _map_range(c, node, socket, ctx):
    kind = MAP_RANGE_TYPES.index(node.interpolation_type)
    clamp = "true" if node.clamp else "false"
    if node.data_type == "FLOAT":
        args = ", ".join(c.input(node, i, ctx, "float").expr for i in range(6))
        return c.temp("float", f"node_map_range({kind}, {clamp}, {args})")
    # FLOAT_VECTOR: each component mapped alone (Blender's vector Map Range).
    ins = [c.input(node, k, ctx, "vec3") for k in ("Vector", "From_Min_FLOAT3", "From_Max_FLOAT3")]
    ins += [c.input(node, k, ctx, "vec3") for k in ("To_Min_FLOAT3", "To_Max_FLOAT3", "Steps_FLOAT3")]
    parts = []
    for comp in "xyz":
        args = ", ".join(f"{v.expr}.{comp}" for v in ins)
        parts.append(f"node_map_range({kind}, {clamp}, {args})")
    return c.temp("vec3", f"vec3({', '.join(parts)})")


@node("ShaderNodeClamp", family="converter")
def _clamp(c, node, socket, ctx):
    v, lo, hi = (c.input(node, k, ctx, "float") for k in ("Value", "Min", "Max"))
    return c.temp("float", f"node_clamp({CLAMP_TYPES.index(node.clamp_type)}, {v.expr}, {lo.expr}, {hi.expr})")


@node("ShaderNodeValToRGB", family="converter")
def _color_ramp(c, node, socket, ctx):
    ramp = node.color_ramp
    fac = c.input(node, "Fac", ctx, "float")
    elements = list(ramp.elements)
    first = len(c.constants)
    for e in elements:
        c.const(tuple(e.color), "vec4")
        c.const(float(e.position), "float")
    args = (
        f"{first}, {len(elements)}, {RAMP_INTERPOLATIONS.index(ramp.interpolation)}, "
        f"{RAMP_MODES.index(ramp.color_mode)}, {RAMP_HUE.index(ramp.hue_interpolation)}"
    )
    v = c.temp("vec4", f"node_color_ramp({fac.expr}, {args})")
    return Value(f"{v.expr}.a", "float") if socket.identifier == "Alpha" else v


def _curve(c, mapping, curve, x):
    """GLSL of curve ``curve`` of CurveMapping ``mapping`` at float expression ``x``: the curve
    tabulated with Blender's own evaluation (constants), read by node_curve."""
    xs = [float(p.location[0]) for p in curve.points]
    lo, hi = min(xs), max(xs)
    if hi - lo < 1e-6:
        hi = lo + 1e-6
    samples = lo + (hi - lo) * np.arange(CURVE_SAMPLES) / (CURVE_SAMPLES - 1)
    ys = [float(mapping.evaluate(curve, float(s))) for s in samples]
    before = ys[0] - float(mapping.evaluate(curve, lo - 1.0))
    after = float(mapping.evaluate(curve, hi + 1.0)) - ys[-1]
    first = len(c.constants)
    for k in range(0, CURVE_SAMPLES, 4):
        c.const(tuple(ys[k : k + 4]), "vec4")
    head = c.const((lo, 1.0 / (hi - lo), before, after), "vec4")
    return f"node_curve({x}, {first}, {CURVE_SAMPLES}, {head.expr})"


@node("ShaderNodeFloatCurve", family="converter")
def _float_curve(c, node, socket, ctx):
    mapping = node.mapping
    mapping.initialize()
    fac, value = c.input(node, "Factor", ctx, "float"), c.input(node, "Value", ctx, "float")
    v = c.temp("float", value.expr)
    curved = c.temp("float", _curve(c, mapping, mapping.curves[0], v.expr))
    return c.temp("float", f"mix({v.expr}, {curved.expr}, {fac.expr})")


@node("ShaderNodeRGBCurve", family="converter")
def _rgb_curve(c, node, socket, ctx):
    """Each channel through the combined curve (C), then its own (R, G, B), after the black
    and white levels, mixed with the input by Fac; alpha kept."""
    mapping = node.mapping
    mapping.initialize()
    fac, col = c.input(node, "Fac", ctx, "float"), c.input(node, "Color", ctx, "vec4")
    black, white = tuple(mapping.black_level), tuple(mapping.white_level)
    src = c.temp("vec4", col.expr)
    x = src
    if black != (0.0, 0.0, 0.0) or white != (1.0, 1.0, 1.0):
        b = c.const(black, "vec3")
        scale = c.const(tuple(1.0 / (w - k) if w != k else 0.0 for w, k in zip(white, black, strict=True)), "vec3")
        x = c.temp("vec4", f"vec4(({src.expr}.rgb - {b.expr}) * {scale.expr}, {src.expr}.a)")
    channels = []
    for i, comp in enumerate("rgb"):
        combined = c.temp("float", _curve(c, mapping, mapping.curves[3], f"{x.expr}.{comp}"))
        channels.append(c.temp("float", _curve(c, mapping, mapping.curves[i], combined.expr)).expr)
    curved = f"vec4({', '.join(channels)}, {src.expr}.a)"
    return c.temp("vec4", f"mix({src.expr}, {curved}, {fac.expr})")


@node("ShaderNodeHueSaturation", family="color")
def _hue_sat(c, node, socket, ctx):
    h, s, v, f = (c.input(node, k, ctx, "float") for k in ("Hue", "Saturation", "Value", "Fac"))
    col = c.input(node, "Color", ctx, "vec4")
    return c.temp("vec4", f"node_hue_saturation({h.expr}, {s.expr}, {v.expr}, {f.expr}, {col.expr})")


@node("ShaderNodeInvert", family="color")
def _invert(c, node, socket, ctx):
    f, col = c.input(node, "Fac", ctx, "float"), c.input(node, "Color", ctx, "vec4")
    return c.temp("vec4", f"node_invert({f.expr}, {col.expr})")


@node("ShaderNodeGamma", family="color")
def _gamma(c, node, socket, ctx):
    col, g = c.input(node, "Color", ctx, "vec4"), c.input(node, "Gamma", ctx, "float")
    return c.temp("vec4", f"node_gamma({col.expr}, {g.expr})")


@node("ShaderNodeBrightContrast", family="color")
def _bright_contrast(c, node, socket, ctx):
    col = c.input(node, "Color", ctx, "vec4")
    b, k = c.input(node, "Bright", ctx, "float"), c.input(node, "Contrast", ctx, "float")
    return c.temp("vec4", f"node_bright_contrast({col.expr}, {b.expr}, {k.expr})")


@node("ShaderNodeSeparateColor", family="color")
def _separate_color(c, node, socket, ctx):
    col = c.input(node, "Color", ctx, "vec4")
    v = c.temp("vec4", f"node_separate_color({COLOR_MODES.index(node.mode)}, {col.expr})")
    index = [s.identifier for s in node.outputs].index(socket.identifier)
    return Value(f"{v.expr}.{'xyzw'[index]}", "float")


@node("ShaderNodeCombineColor", family="color")
def _combine_color(c, node, socket, ctx):
    x, y, z = (c.input(node, i, ctx, "float") for i in range(3))
    return c.temp("vec4", f"node_combine_color({COLOR_MODES.index(node.mode)}, {x.expr}, {y.expr}, {z.expr})")


@node("ShaderNodeSeparateRGB")
def _separate_rgb(c, node, socket, ctx):
    col = c.input(node, "Image", ctx, "vec4")
    return Value(f"({col.expr}).{'rgb'[['R', 'G', 'B'].index(socket.identifier)]}", "float")


@node("ShaderNodeCombineRGB")
def _combine_rgb(c, node, socket, ctx):
    x, y, z = (c.input(node, i, ctx, "float") for i in range(3))
    return c.temp("vec4", f"vec4({x.expr}, {y.expr}, {z.expr}, 1.0)")


@node("ShaderNodeSeparateXYZ")
def _separate_xyz(c, node, socket, ctx):
    v = c.input(node, "Vector", ctx, "vec3")
    return Value(f"({v.expr}).{'xyz'[['X', 'Y', 'Z'].index(socket.identifier)]}", "float")


@node("ShaderNodeCombineXYZ")
def _combine_xyz(c, node, socket, ctx):
    x, y, z = (c.input(node, i, ctx, "float") for i in range(3))
    return c.temp("vec3", f"vec3({x.expr}, {y.expr}, {z.expr})")


# --- vectors ------------------------------------------------------------------------------


@node("ShaderNodeBump", family="input")
def _bump(c, node, socket, ctx):
    strength, dist = c.input(node, "Strength", ctx, "float"), c.input(node, "Distance", ctx, "float")
    height = c.input(node, "Height", ctx, "float")
    n = c.input(node, "Normal", ctx, "vec3") if c.linked(node, "Normal") else Value("N", "vec3")
    invert = "true" if node.invert else "false"
    h = c.temp("float", height.expr)
    return c.temp("vec3", f"node_bump({strength.expr}, {dist.expr}, {h.expr}, {n.expr}, front, {invert})")


@node("ShaderNodeMapping", family="vector")
def _mapping(c, node, socket, ctx):
    c.families.add("math")
    v = c.input(node, "Vector", ctx, "vec3")
    kind = MAPPING_TYPES.index(node.vector_type)
    loc = c.input(node, "Location", ctx, "vec3") if kind < 2 else Value("vec3(0.0)", "vec3")
    rot, scale = c.input(node, "Rotation", ctx, "vec3"), c.input(node, "Scale", ctx, "vec3")
    return c.temp("vec3", f"node_mapping({kind}, {v.expr}, {loc.expr}, {rot.expr}, {scale.expr})")


# --- textures -----------------------------------------------------------------------------


def _blender_5():
    """The running Blender is 5.x or later (Voronoi and Magic changed there)."""
    import bpy

    return tuple(bpy.app.version) >= (5, 0, 0)


def _dimensions(node, prop):
    """A texture node's dimensions property ('1D' .. '4D') as 1 .. 4."""
    return int(str(getattr(node, prop, "3D"))[0])


def _glsl_bool(value):
    return "true" if value else "false"


def _texture_point(c, node, ctx, dims, scale, finite_after=False):
    """The scaled coordinate a hashed texture reads for ``dims`` dimensions (1D: W; 2D: Vector.xy;
    3D: Vector; 4D: Vector and W), non-finite inputs as 0, as Blender's node functions take it."""
    parts = []
    if dims >= 2:
        v = c.texture_vector(node, ctx)
        parts.append(f"texture_finite({v.expr}) * {scale.expr}")
    if dims in (1, 4):
        w = c.input(node, "W", ctx, "float")
        parts.append(f"texture_finite({w.expr}) * {scale.expr}")
    if finite_after:
        parts = [f"texture_finite({p})" for p in parts]
    if dims == 1:
        return c.temp("float", parts[0])
    if dims == 2:
        return c.temp("vec2", f"({parts[0]}).xy")
    if dims == 3:
        return c.temp("vec3", parts[0])
    return c.temp("vec4", f"vec4({parts[0]}, {parts[1]})")


def _rgba(value):
    """A vec4 expression's colour with alpha 1 (the texture functions pack Fac in .a)."""
    return Value(f"vec4({value.expr}.rgb, 1.0)", "vec4")


@node("ShaderNodeTexNoise", family="texture_noise")
def _noise(c, node, socket, ctx):
    dims = _dimensions(node, "noise_dimensions")
    kind = NOISE_TYPES.index(getattr(node, "noise_type", "FBM"))
    normalize = _glsl_bool(getattr(node, "normalize", True))
    scale = c.input(node, "Scale", ctx, "float")
    p = _texture_point(c, node, ctx, dims, scale)
    args = [c.input(node, k, ctx, "float").expr for k in ("Detail", "Roughness", "Lacunarity")]
    args += [
        c.input(node, k, ctx, "float").expr if _has(node, k) else d for k, d in (("Offset", "0.0"), ("Gain", "1.0"))
    ]
    args.append(c.input(node, "Distortion", ctx, "float").expr)
    v = c.temp("vec4", f"node_tex_noise_at({p.expr}, {', '.join(args)}, {kind}, {normalize})")
    return Value(f"{v.expr}.a", "float") if socket.identifier == "Fac" else _rgba(v)


def _has(node, key):
    return any(s.identifier == key or s.name == key for s in node.inputs)


@node("ShaderNodeTexVoronoi", family="texture_voronoi")
def _voronoi(c, node, socket, ctx):
    dims = _dimensions(node, "voronoi_dimensions")
    feature = VORONOI_FEATURES.index(node.feature)
    metric = VORONOI_METRICS.index(getattr(node, "distance", "EUCLIDEAN"))
    normalize = _glsl_bool(getattr(node, "normalize", False))
    scale = c.input(node, "Scale", ctx, "float")
    p = _texture_point(c, node, ctx, dims, scale, finite_after=True)
    keys = ("Detail", "Roughness", "Lacunarity", "Smoothness", "Exponent", "Randomness")
    defaults = {"Detail": "0.0", "Roughness": "0.5", "Lacunarity": "2.0"}  # sockets Blender 3.x lacks
    args = [c.input(node, k, ctx, "float").expr if _has(node, k) else defaults[k] for k in keys]
    hash_mode = 1 if _blender_5() else 0  # VORONOI_HASH_INT on Blender 5, VORONOI_HASH_FLOAT before
    dist, col = c.temp("float", "0.0"), c.temp("vec3", "vec3(0.0)")
    pos, rad = c.temp("vec4", "vec4(0.0)"), c.temp("float", "0.0")
    c.lines.append(
        f"  node_tex_voronoi_at({p.expr}, {feature}, {metric}, {scale.expr}, {', '.join(args)}, {normalize}, "
        f"{hash_mode}, {dist.expr}, {col.expr}, {pos.expr}, {rad.expr});"
    )
    out = socket.identifier
    if out == "Color":
        return Value(f"vec4({col.expr}, 1.0)", "vec4")
    if out == "Position":
        return Value(f"{pos.expr}.xyz", "vec3")
    if out == "W":
        return Value(f"{pos.expr}.w", "float")
    if out == "Radius":
        return rad
    return dist


@node("ShaderNodeTexWhiteNoise", family="texture_white_noise")
def _white_noise(c, node, socket, ctx):
    dims = _dimensions(node, "noise_dimensions")
    v = c.texture_vector(node, ctx) if dims >= 2 else Value("vec3(0.0)", "vec3")
    w = c.input(node, "W", ctx, "float") if dims in (1, 4) else Value("0.0", "float")
    t = c.temp("vec4", f"node_tex_white_noise({dims}, {v.expr}, {w.expr})")
    return Value(f"{t.expr}.a", "float") if socket.identifier == "Value" else _rgba(t)


@node("ShaderNodeTexWave", family="texture_wave")
def _wave(c, node, socket, ctx):
    kind = WAVE_TYPES.index(node.wave_type)
    direction = WAVE_BANDS.index(node.bands_direction) if kind == 0 else WAVE_RINGS.index(node.rings_direction)
    profile = WAVE_PROFILES.index(node.wave_profile)
    p = c.texture_vector(node, ctx)
    keys = ("Scale", "Distortion", "Detail", "Detail Scale", "Detail Roughness", "Phase Offset")
    args = ", ".join(c.input(node, k, ctx, "float").expr for k in keys)
    v = c.temp("vec4", f"node_tex_wave({p.expr}, {args}, {kind}, {direction}, {profile})")
    return Value(f"{v.expr}.a", "float") if socket.identifier == "Fac" else _rgba(v)


@node("ShaderNodeTexMagic", family="texture_magic")
def _magic(c, node, socket, ctx):
    p = c.texture_vector(node, ctx)
    scale, dist = c.input(node, "Scale", ctx, "float"), c.input(node, "Distortion", ctx, "float")
    depth = c.const(float(node.turbulence_depth), "float")
    wrap = 1 if _blender_5() else 0  # MAGIC_WRAP_SCALED on Blender 5, MAGIC_WRAP_UNSCALED before
    v = c.temp("vec4", f"node_tex_magic({p.expr}, {scale.expr}, {dist.expr}, int({depth.expr}), {wrap})")
    return Value(f"{v.expr}.a", "float") if socket.identifier == "Fac" else _rgba(v)


@node("ShaderNodeTexBrick", family="texture_brick")
def _brick(c, node, socket, ctx):
    p = c.texture_vector(node, ctx)
    colours = ", ".join(c.input(node, k, ctx, "vec4").expr + ".rgb" for k in ("Color1", "Color2", "Mortar"))
    keys = ("Scale", "Mortar Size", "Mortar Smooth", "Bias", "Brick Width", "Row Height")
    values = ", ".join(c.input(node, k, ctx, "float").expr for k in keys)
    props = c.const((node.offset, node.offset_frequency, node.squash, node.squash_frequency), "vec4")
    v = c.temp(
        "vec4",
        f"node_tex_brick({p.expr}, {colours}, {values}, {props.expr}.x, int({props.expr}.y), "
        f"{props.expr}.z, int({props.expr}.w))",
    )
    return Value(f"{v.expr}.a", "float") if socket.identifier == "Fac" else _rgba(v)


@node("ShaderNodeTexChecker", family="texture_checker")
def _checker(c, node, socket, ctx):
    p = c.texture_vector(node, ctx)
    a, b = c.input(node, "Color1", ctx, "vec4"), c.input(node, "Color2", ctx, "vec4")
    scale = c.input(node, "Scale", ctx, "float")
    v = c.temp("vec4", f"node_tex_checker({p.expr}, {a.expr}.rgb, {b.expr}.rgb, {scale.expr})")
    return Value(f"{v.expr}.a", "float") if socket.identifier == "Fac" else _rgba(v)


@node("ShaderNodeTexGradient", family="texture_gradient")
def _gradient(c, node, socket, ctx):
    p = c.texture_vector(node, ctx)
    v = c.temp("vec4", f"node_tex_gradient({p.expr}, {GRADIENT_TYPES.index(node.gradient_type)})")
    return Value(f"{v.expr}.a", "float") if socket.identifier == "Fac" else _rgba(v)


@node("ShaderNodeTexImage")
def _image(c, node, socket, ctx):
    image = node.image
    if image is None:
        c.messages.append("an Image Texture node without an image")
        return Value("vec4(0.0, 0.0, 0.0, 1.0)" if socket.identifier == "Color" else "0.0", SOCKET_TYPES[socket.type])
    if node.projection != "FLAT":
        c.messages.append(f"image projection {node.projection} (flat UV is used)")
    if node.interpolation in {"Cubic", "Smart"}:
        c.messages.append(f"{node.interpolation} interpolation (drawn as Linear)")
    ref = NodeImage(image.name_full, node.interpolation, node.extension)
    if ref not in c.images:
        if len(c.images) >= MAX_IMAGES:
            raise Fallback(f"more than {MAX_IMAGES} image textures")
        c.images.append(ref)
    index = c.images.index(ref)
    uv = c.input(node, "Vector", ctx, "vec3") if c.linked(node, "Vector") else c.uv("")
    mode = f"ivec4({IMAGE_INTERPOLATION.get(ref.interpolation, 1)}, {IMAGE_EXTENSION.get(ref.extension, 0)}, 0, 0)"
    premultiplied = f"(image_premultiplied & {1 << index}) != 0"  # set per draw (``TextureCache``)
    texel = c.temp("vec4", f"sample_image(node_image_{index}, ({uv.expr}).xy, {mode}, {premultiplied})")
    return Value(f"{texel.expr}.a", "float") if socket.identifier == "Alpha" else texel


# Principled BSDF inputs Penumbra does not draw, named when they would change the surface: a
# weight above 0, or any of them linked. (IOR, Specular IOR Level and Specular Tint are drawn:
# node_principled_f0.)
PRINCIPLED_UNREAD = (
    "Transmission Weight",
    "Transmission",
    "Coat Weight",
    "Sheen Weight",
    "Subsurface Weight",
    "Anisotropic",
    "Thin Film Thickness",
)


def anisotropy_unread(node):
    """["Anisotropy"] for a Glossy (Anisotropic) BSDF whose Anisotropy is linked or not 0 (what
    NODE_ANISO draws), else []."""
    sock = node.inputs.get("Anisotropy")
    if sock is not None and (sock.is_linked or abs(float(sock.default_value)) > 0.0):
        return ["Anisotropy"]
    return []


def principled_unread(node):
    """Names of the inputs of Principled BSDF ``node`` that change its surface and are not
    drawn (``PRINCIPLED_UNREAD``)."""
    out = []
    for name in PRINCIPLED_UNREAD:
        sock = node.inputs.get(name)
        if sock is not None and (sock.is_linked or float(sock.default_value) > 0.0):
            out.append(name)
    return out
