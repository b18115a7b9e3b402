"""Blender's further passes (``FrameRequest.passes``; docs/passes.md): after each sample's lit
pass the seen surfaces are drawn again over the z-buffer it left. Data and colour passes and
Shader AOVs: up to six a draw of their own entry shader (``shaders/lit_passes.frag.glsl``),
averaged over the samples like Combined (its film accumulation, filter and adaptive mask) or
taken from the centred sample as Cycles takes them (Position, Object and Material Index). Light
passes and light groups: the lit program again with the frame's techniques and one
``LIGHT_PASS`` variant each, averaged, the world's light in them shadowed at the resolve as
Combined's (``FilmPart.resolve_light``). Cryptomatte's ids are read back each sample and ranked
on the CPU (``frame/cryptomatte.py``).

A frame that asks for no such pass does not register this technique: no draw, no target."""

from ....shaders.loader import ProgramPart, set_uniforms
from ...gpu_pool import new_texture
from .. import cryptomatte, sampling
from ..film import FilmPart, clear_zero
from ..film_programs import SCALED_COPY, WEIGHTED_RESOLVE
from .base import Feature, outputs_of

# Each pass a frame can ask for: its id in lit_passes.frag.glsl, and how the samples give it
# (MEAN: averaged as Combined; CENTRE: the centred sample's; IDS: read back every sample).
MEAN, CENTRE, IDS = "MEAN", "CENTRE", "IDS"
PASSES = {
    "POSITION": (1, CENTRE),
    "OBJECT_INDEX": (2, CENTRE),
    "MATERIAL_INDEX": (3, CENTRE),
    "DIFFUSE_COLOR": (4, MEAN),
    "GLOSSY_COLOR": (5, MEAN),
    "TRANSMISSION_COLOR": (6, MEAN),
    "ENVIRONMENT": (7, MEAN),
    "DENOISING_ALBEDO": (8, MEAN),
    "DENOISING_NORMAL": (9, MEAN),
    "CRYPTOMATTE": (10, IDS),
    "UV": (11, MEAN),
    "DRAW": (12, CENTRE),  # the draw at each pixel (the Vector pass: ``vectors.py``)
}
# Blender's light passes: the light of one kind of lobe (a lit variant of its own, LIGHT_PASS in
# lib/lit_surface.glsl), averaged like Combined, and the Color pass that divides it into the
# Direct or Indirect pass (Cycles' algebra: Direct x Color is the light).
LIGHT_PASSES = {
    "DIFFUSE_DIRECT": (1, "DIFFUSE_COLOR"),
    "DIFFUSE_INDIRECT": (2, "DIFFUSE_COLOR"),
    "GLOSSY_DIRECT": (3, "GLOSSY_COLOR"),
    "GLOSSY_INDIRECT": (4, "GLOSSY_COLOR"),
    "TRANSMISSION_DIRECT": (5, "TRANSMISSION_COLOR"),
}
LIGHT = "LIGHT"
# The world's light each light pass carries, by lobe (diffuse, specular): a technique that
# shadows it at the resolve does so for the pass too (``FilmPart.resolve_light``: the ratio's).
_WORLD_LOBES = {"DIFFUSE_DIRECT": (True, False), "GLOSSY_DIRECT": (False, True)}
AOV_COLOR, AOV_VALUE = 32, 64  # + the AOV Output node's index in its tree (lit_passes.frag.glsl)
MAX_TARGETS = 6  # colour targets Blender's gpu module binds

# The entry shader of the passes' draws and the per-draw values it reads.
ENTRY = ProgramPart(
    "passes",
    fragment="lit_passes.frag.glsl",
    # (Object Index, Material Index, Cryptomatte's object and material ids), (its asset id, the
    # draw's number + 1).
    push_constants=(("VEC4", "pass_ids"), ("VEC2", "pass_more")),
)


GROUP = "LIGHTGROUP:"  # + a light group's name: its Combined before the post stack
# Techniques whose light a light group pass leaves out (what they add mixes every group's).
_MIXED_ACROSS_GROUPS = ("reflections", "planar", "cubes", "refraction", "bounce", "subsurface")
LIGHT_PASS_GROUP = 6


# The entry of a draw that writes the UV pass: the mesh's UV map as vertex data (extraction reads
# every mesh's active render map when the UV pass is asked: ``SceneCache.uv_pass``).
ENTRY_UV = ProgramPart(
    "passes_uv",
    fragment=ENTRY.fragment,
    push_constants=ENTRY.push_constants,
    vertex_in=(("VEC2", "uv"),),
    varyings=(("smooth", "VEC2", "v_uv"),),
    defines=(("HAS_UV", True),),
)


def _mode(key):
    if key in LIGHT_PASSES or key.startswith(GROUP):
        return LIGHT
    return PASSES[key][1] if key in PASSES else MEAN


def frame_keys(keys):
    """What a frame draws for the passes ``keys``: each, and the Color pass a light pass is
    divided by."""
    out = list(keys)
    out += [LIGHT_PASSES[k][1] for k in keys if k in LIGHT_PASSES and LIGHT_PASSES[k][1]]
    return tuple(dict.fromkeys(out))


def groups(keys):
    """The draws of a frame's passes but the light passes: (mode, keys) with at most
    MAX_TARGETS keys each; the centred sample's apart from those of every sample."""
    every = [k for k in keys if _mode(k) in (MEAN, IDS)]
    centre = [k for k in keys if _mode(k) == CENTRE]
    out = []
    for mode, ks in ((MEAN, every), (CENTRE, centre)):
        out += [(mode, tuple(ks[i : i + MAX_TARGETS])) for i in range(0, len(ks), MAX_TARGETS)]
    return out


def group_part(keys, tree):
    """The ``ProgramPart`` of one draw of ``keys``: its outputs and which pass each writes;
    an AOV the material's ``tree`` does not write is 0 there."""
    defines = [("PASS_COUNT", len(keys))]
    for slot, key in enumerate(keys):
        if key.startswith("AOV_"):
            kind, name = key[4:].split(":", 1)
            aovs = tree.aovs if tree is not None else ()
            which = (AOV_VALUE if kind == "VALUE" else AOV_COLOR) + aovs.index(name) if name in aovs else 0
        else:
            which = PASSES[key][0]
        defines.append((f"PASS_{slot}", which))
    name = "pass" + "_".join(str(v) for _k, v in defines[1:])
    outputs = tuple(("VEC4", f"out_pass{i}") for i in range(1, len(keys)))
    return ProgramPart(name, outputs=outputs, defines=tuple(defines))


class PassTargets(FilmPart):
    """The passes' targets: one RGBA32F a pass (what a sample's draw writes; after the frame's
    resolve, a mean pass's average) and, in a frame of several samples, each mean pass's
    accumulation with the colour's weights (``Film.copy``: its filter and adaptive mask)."""

    name = "passes"

    def __init__(self):
        self.size = None
        self.keys = ()
        self.sample = {}  # key -> texture
        self.accum = {}  # key -> (accumulation, its framebuffer)
        self.fbs = {}
        self.scratch = []  # what a light pass's draw writes of the techniques' targets (not kept)
        self.world_groups = set()  # the light group passes the world's light is in

    def ensure(self, film, keys, scratch=0):
        """The targets of ``keys`` at the film's size, and ``scratch`` targets for the
        techniques' outputs a light pass's draw writes besides its own."""
        import gpu

        if self.size != film.size or self.keys != tuple(keys) or len(self.scratch) < scratch:
            self.release(film)
            self.size, self.keys = film.size, tuple(keys)
            self.scratch = [new_texture(film.pool, film.size, "RGBA32F") for _ in range(scratch)]
        for key in keys:
            if key not in self.sample:
                self.sample[key] = new_texture(film.pool, film.size, "RGBA32F")
        for _mode_of, ks in groups(keys):
            if ks not in self.fbs:
                slots = tuple(self.sample[k] for k in ks)
                self.fbs[ks] = gpu.types.GPUFrameBuffer(depth_slot=film.zbuffer, color_slots=slots)
        return self.sample

    def light_framebuffer(self, film, key, outputs):
        """A light pass's framebuffer: its target, then ``outputs`` scratch targets."""
        import gpu

        which = (key, outputs)
        if which not in self.fbs:
            slots = (self.sample[key], *self.scratch[:outputs])
            self.fbs[which] = gpu.types.GPUFrameBuffer(depth_slot=film.zbuffer, color_slots=slots)
        return self.fbs[which]

    def framebuffer_of(self, keys):
        return self.fbs[keys]

    def begin(self, film):
        import gpu

        for key in self.keys:
            if _mode(key) not in (MEAN, LIGHT):
                continue
            if key not in self.accum:
                target = new_texture(film.pool, film.size, "RGBA32F")
                self.accum[key] = (target, gpu.types.GPUFrameBuffer(color_slots=(target,)))
            clear_zero(self.accum[key][0])

    def copies(self, film, sample):
        return [(self.sample[key], target) for key, (target, _fb) in self.accum.items()]

    def accumulated(self, film):
        """Each averaged pass's (accumulation, this sample's target): where settling keeps its
        pilot's value, the passes keep the pilot's too, as Combined does."""
        return [(accum, self.sample[key]) for key, (accum, _fb) in self.accum.items()]

    def resolve(self, film, framebuffer=None):
        """Each mean pass's average into its target (not into ``framebuffer``: that is the
        colour's mean alone, ``Film.mean_into``)."""
        if framebuffer is not None:
            return
        import gpu

        for key, (accum, _fb) in self.accum.items():
            out = gpu.types.GPUFrameBuffer(color_slots=(self.sample[key],))
            lobes = _WORLD_LOBES.get(key) or ((True, True) if key in self.world_groups else (False, False))
            if any(lobes) and any(part.resolve_light(film, accum, out, lobes, self.scratch[0]) for part in film.parts):
                continue  # a technique took its share out (the world ratio's)
            if film.weight is not None:
                film.fullscreen(WEIGHTED_RESOLVE, out, {"src_color": accum, "weight": film.weight}, {})
            else:
                total = film.weight_sum
                film.fullscreen(SCALED_COPY, out, {"src_color": accum}, {"scale": 1.0 / total if total > 0 else 0.0})

    def bytes_per_pixel(self, film):
        return 16 * (len(self.sample) + len(self.accum) + len(self.scratch))

    def release(self, film):
        film.give([*self.sample.values(), *(t for t, _fb in self.accum.values()), *self.scratch])
        self.sample, self.accum, self.fbs, self.scratch = {}, {}, {}, []
        self.size, self.keys = None, ()


class Passes(Feature):
    """The passes a final render's view layer asks for (``FrameRequest.passes``)."""

    name = "passes"

    def __init__(self, renderer):
        super().__init__(renderer)
        self.targets = PassTargets()
        self.crypto = None  # cryptomatte.Accumulator of the frame
        self._centre_draws = []  # (motion key, world matrix) of the centred sample's draws, by number

    def wanted(self, frame):
        return bool(frame.request.passes)

    def plan(self, frame):
        keys = frame_keys(frame.request.passes)
        world = frame.snapshot.world
        world_group = getattr(world, "lightgroup", "") if world is not None else ""
        self.targets.world_groups = {GROUP + world_group} if world_group else set()
        # A light pass's draw writes the targets the techniques' parts write beside the colour
        # (the world ratio's): into scratch targets (the lit pass's own are this sample's).
        scratch = 4 if any(_mode(k) == LIGHT for k in keys) and frame.accumulate else 0
        self.targets.ensure(self.renderer.film, keys, scratch)
        if "CRYPTOMATTE" in keys and frame.request.samples[0] == 0:
            levels, kinds = frame.request.cryptomatte
            # Room for a few ids beyond those written: an id met late can still outrank one seen early.
            self.crypto = cryptomatte.Accumulator(frame.size, capacity=min(int(levels), 16) + 2, kinds=kinds)
            seen = [d.instance for d in frame.draws if d.instance.camera]
            self.crypto.names = (
                sorted({i.crypto_names[0] for i in seen}),
                sorted({m.name for i in seen for m in i.materials if m is not None}),
                sorted({i.crypto_names[1] for i in seen}),
            )

    def film_part(self, frame):
        return self.targets

    def after_lit(self, frame, sample):
        """The sample's pass draws: those of every sample, and at the centred sample (the
        first) those it alone gives; Cryptomatte's ids read back and added."""
        if sample.settle_test:
            return
        renderer = self.renderer
        targets = self.targets
        keys = frame_keys(frame.request.passes)
        data = sample.data
        # The sample's own draws (motion blur gives each sample its list), numbered for DRAW.
        values = _draw_values({id(d): i for i, d in enumerate(sample.draws)})
        if sample.index == 0 and not sample.pilot:
            self._centre_draws = [(d.instance.motion_key, d.instance.matrix) for d in sample.draws]
        outputs = max(outputs_of(data.parts), outputs_of(data.blended_parts))
        for key in keys:
            if _mode(key) != LIGHT:
                continue  # (a pilot sample, settling's, draws what a settled pixel keeps of it)
            group = _group_draw(frame, sample, key[len(GROUP) :]) if key.startswith(GROUP) else None
            if group is not None:
                part, per_draw, masks = group
            else:
                part = ProgramPart(f"light{LIGHT_PASSES[key][0]}", defines=(("LIGHT_PASS", LIGHT_PASSES[key][0]),))
                per_draw = masks = None
            targets.sample[key].clear(format="FLOAT", value=(0.0, 0.0, 0.0, 0.0))
            if key in targets.world_groups and not frame.settings.film_transparent:
                renderer.lit_pass.background_into(targets.sample[key], frame, sample)  # the world seen
            fbs = (
                targets.light_framebuffer(renderer.film, key, outputs_of(data.parts)),
                targets.light_framebuffer(renderer.film, key, outputs_of(data.blended_parts)),
            )
            if outputs > len(targets.scratch):
                raise RuntimeError("a technique writes more targets than the light passes' scratch holds")
            renderer.lit_pass.draw_light(sample, fbs, part, per_draw, masks)
        for mode, ks in groups(keys):
            if mode == CENTRE and (sample.index != 0 or sample.pilot):
                continue
            fb = targets.framebuffer_of(ks)
            with fb.bind():
                fb.clear(color=(0.0, 0.0, 0.0, 0.0))
            if "ENVIRONMENT" in ks:
                renderer.lit_pass.background_into(targets.sample["ENVIRONMENT"], frame, sample)
            entry = ENTRY_UV if "UV" in ks else ENTRY
            renderer.lit_pass.draw_apart(sample, fb, entry, lambda tree, ks=ks: group_part(ks, tree), values)
        if self.crypto is not None and not sample.pilot:
            from ..film import texture_array

            with frame.clock.waiting():
                ids = texture_array(targets.sample["CRYPTOMATTE"], 4)
            taps = sampling.sample_taps(sample.index, frame.settings.filter_size) if frame.accumulate else [(0, 0, 1.0)]
            self.crypto.add(ids[..., :3], taps, sampling.gathers(frame.settings.filter_size) and frame.accumulate)

    def resolve(self, frame):
        """What the frame's passes are (``frame.pass_outputs``): their targets, and
        Cryptomatte's ranked (id, coverage) layers."""
        keys = frame_keys(frame.request.passes)
        # (Asked here: the frame's techniques are known once every one planned.)
        if any(k.startswith(GROUP) for k in keys) and any(frame.has(t) for t in _MIXED_ACROSS_GROUPS):
            frame.stats.messages.append(
                "Penumbra: light group passes hold each group's direct light, world and emission; what surfaces "
                "reflect or refract of the scene and the diffuse bounce are in Combined alone"
            )
        outputs = {k: self.targets.sample[k] for k in keys if k != "CRYPTOMATTE"}
        if self.crypto is not None:
            outputs["CRYPTOMATTE"] = self.crypto
        outputs["ORIGIN"] = tuple(float(x) for x in frame.origin)  # what Position is relative to
        if "DRAW" in outputs:  # the centred sample's draws' instances, by number (the Vector pass)
            outputs["DRAWS"] = self._centre_draws
        frame.pass_outputs = outputs

    def memory_bytes(self, frame):
        """Its targets in a one-sample frame (a frame of several counts them as the film's part)."""
        if frame.accumulate:
            return 0
        return self.targets.bytes_per_pixel(self.renderer.film) * frame.size[0] * frame.size[1]

    def release(self):
        self.targets.release(self.renderer.film)
        self.crypto = None


def _group_draw(frame, sample, name):
    """A light group pass's draw: (its ``ProgramPart``, per-draw values, light masks by draw):
    the group's lights (world directions with the world), its objects' emission, the world's
    SH light and image when the world is in the group."""
    world = frame.snapshot.world
    world_in = bool(world is not None and getattr(world, "lightgroup", "") == name)
    part = ProgramPart(
        f"group{int(world_in)}",
        defines=(("LIGHT_PASS", LIGHT_PASS_GROUP), ("LIGHT_GROUP_WORLD", world_in)),
        push_constants=(("FLOAT", "group_emission"),),
    )
    lights, order = sample.lights, sample.data.order
    words = [0, 0, 0, 0]
    for j, i in enumerate(order):
        light = lights[i]
        if (light.world and world_in) or (not light.world and getattr(light, "lightgroup", "") == name):
            words[j >> 5] |= 1 << (j & 31)
    linked = sample.masks
    masks = {}
    for d in sample.seen:
        own = linked[id(d)] if linked is not None else (-1, -1, -1, -1)
        both = [(w & (o & 0xFFFFFFFF)) for w, o in zip(words, own, strict=True)]
        masks[id(d)] = tuple(w - (1 << 32) if w >= 1 << 31 else w for w in both)

    def per_draw(shader, draw, mat):
        set_uniforms(shader, {"group_emission": 1.0 if draw.instance.lightgroup == name else 0.0})

    return part, per_draw, masks


def _draw_values(numbers):
    """A draw's own values: its object's and material's Pass Index, its Cryptomatte ids, its
    number in the frame's draw list + 1 (``numbers``: {id(draw): number})."""

    def per_draw(shader, draw, mat):
        obj, material, asset = cryptomatte.draw_ids(draw.instance, mat)
        index = float(draw.instance.pass_index), float(getattr(mat, "pass_index", 0))
        more = (asset, float(numbers.get(id(draw), -1) + 1))
        set_uniforms(shader, {"pass_ids": (*index, obj, material), "pass_more": more})

    return per_draw


def passes_of(frame):
    """{key: texture or cryptomatte.Accumulator} of a rendered frame (empty without passes)."""
    return dict(getattr(frame, "pass_outputs", None) or {})
