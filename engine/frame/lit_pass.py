"""The lit pass: every visible part shaded by its material variant (``programs.LitKey``)
with the frame's lights and shadow atlas, into the film's targets; and the world's
Environment Texture behind it."""

import contextlib
import dataclasses
from dataclasses import dataclass

import numpy as np

from ...shaders.loader import Program, set_uniforms
from ..gpu_pool import UniformBlocks
from ..shadows import kernels, lightspace
from .draw_list import front_to_back
from .programs import (
    COUNTED_PART,
    EMISSION_ONLY,
    EMISSION_PART,
    ENTRY_PARTS,
    JITTER_SIZE,
    SHADOW_SAMPLER,
    image_premultiplied_bits,
    lit_key,
    terminator_uniforms,
)

# The material feature of surfaces that transmit light (``materials.Material.transmission``).
TRANSMISSION = "TRANSMISSION"

# The world's Environment Texture behind everything (materials.World.image).
BACKGROUND = Program(
    name="background",
    vertex="fullscreen.vert.glsl",
    fragment="background.frag.glsl",
    libs=("lib/common.glsl", "lib/material.glsl"),
    vertex_in=(("VEC2", "pos"),),
    push_constants=(
        ("MAT4", "inverse_view_proj"),
        ("VEC2", "viewport_origin"),
        ("VEC2", "viewport_size"),
        ("FLOAT", "strength"),
        ("FLOAT", "env_premultiplied"),  # 1: Blender stores the image premultiplied
    ),
    samplers=(("FLOAT_2D", "env"),),
    outputs=(("VEC4", "out_color"),),
)


class LitPass:
    """The lit pass's GPU state of one renderer: its uniform blocks, the jittered-disk and
    light-bin textures. ``caches``: the renderer's ``GpuCaches`` (programs, material blocks,
    images); ``film``: the film it draws into."""

    def __init__(self, caches, film):
        self.caches = caches
        self.shaders = caches.shaders
        self.materials = caches.materials
        self.textures = caches.textures
        self.film = film
        self._ubos = UniformBlocks()
        self._jitter_tex = {}  # disk samples -> their texture
        self._bins_zero = None
        self._entries_memo = None  # (draws, key, entries): ``_entries``
        self._jitter_dummy = None
        self._bins_tex = None
        self._dummy_shadow = None
        self.uploaded = 0  # bytes sent to the GPU since creation (uniform blocks, textures of data)

    def draw(self, frame, sample):
        """The film's lit pass of ``sample`` (``renderer.Sample``: its draws the camera sees,
        view camera, frame data, atlas and light masks) in ``frame`` (``renderer.FramePlan``):
        every visible part, grouped by material variant: opaque and alpha-hashed parts nearest
        first, then alpha-blended parts farthest first, blended over them (their depth, normal
        and shadow stay those of what is behind; EEVEE too keeps blended surfaces out of its
        depth). The techniques' GPU work over the frame block (``FrameData.begins``: the world
        occlusion's horizons) runs before the draws."""
        import gpu

        film, data, camera, stats = self.film, sample.data, sample.view_camera, sample.stats
        aux = frame.aux
        snapshot = frame.snapshot
        world_data, world_color = snapshot.world, snapshot.world_color
        # Transparent film: the background is RGBA 0 (premultiplied), as Blender's engines write it.
        # A lit debug view's values start at 0 where no surface is (``DEBUG_LIT``).
        transparent = frame.settings.film_transparent or data.variant.debug
        bg = (0.0, 0.0, 0.0, 0.0) if transparent else (*map(float, world_color[:3]), 1.0)
        emission = frame.emission
        counted = film.fb_counted is not None and not aux  # the shading count of tests
        # A technique's targets of its own beside the pass's (its part adds outputs, the film
        # holds them: ``film.FilmPart``). Blender's gpu module binds six colour
        # targets: with them the Emission pass is drawn apart, over the z-buffer the lit pass leaves.
        writes = any(part.outputs for part in data.parts)
        own = film.lit_part if writes else None
        if writes and own is None:
            raise RuntimeError("a technique's lit part writes targets the film does not hold")
        emission_apart = own is not None and emission
        fb = film.lit_framebuffer(aux, emission and not emission_apart, counted, own)
        film.clear(bg, aux, emission, own)
        # Adaptive sampling: where a pixel converged the nearest depth goes first, so nothing
        # (surface or world) is drawn there; the pixel is not shaded again.
        converged = film.mask is not None
        if converged:
            film.mask_depth(fb)
        if world_data is not None and world_data.image is not None and not transparent:
            self._background(film, world_data, camera, frame.origin, "LESS_EQUAL" if converged else "NONE")
        opaque, blended, parts = self._entries(sample.seen, camera, sample.atlas, stats, hashed_last=False)
        # Transmissive surfaces after the others, over what they see through (``LitPart.between``:
        # the refraction's copy of the colour so far); without it they draw as the others.
        transmissive = [e for e in opaque if TRANSMISSION in e[0]] if data.betweens else []
        if transmissive:
            opaque = [e for e in opaque if TRANSMISSION not in e[0]]
        if data.begins:
            block = self._ubo("frame", data.frame)
            for begin in data.begins:
                begin(block, stats)
        submit = _Submission(self, sample, parts)
        submit.emission = emission and not emission_apart
        submit.counted = counted
        width, height = film.size
        with fb.bind():
            gpu.state.viewport_set(0, 0, width, height)
            if not converged:
                fb.clear(depth=1.0)
            gpu.state.depth_test_set("LESS_EQUAL")
            gpu.state.depth_mask_set(True)
            submit.draw(opaque, aux)
        if transmissive:
            for between in data.betweens:
                between(film, stats)
            submit.rebind()
            with fb.bind():
                gpu.state.viewport_set(0, 0, width, height)
                gpu.state.depth_test_set("LESS_EQUAL")
                gpu.state.depth_mask_set(True)
                submit.draw(transmissive, aux)
            opaque = opaque + transmissive
        if emission_apart and opaque:
            submit.rebind(counted=False)
            with film.emission_framebuffer().bind():
                gpu.state.viewport_set(0, 0, width, height)
                gpu.state.depth_test_set("LESS_EQUAL")
                gpu.state.depth_mask_set(False)
                submit.draw(opaque, False, emission_only=True)
        if blended:
            submit.rebind(counted=False)  # blended surfaces draw into the colour target alone
            with film.blend_framebuffer(own).bind():
                gpu.state.viewport_set(0, 0, width, height)
                gpu.state.depth_test_set("LESS_EQUAL")
                gpu.state.depth_mask_set(False)
                gpu.state.blend_set("ALPHA_PREMULT")
                submit.draw(blended, False, blended=True)
                gpu.state.blend_set("NONE")
        _reset_state(stats)

    def draw_apart(self, sample, framebuffer, entry, part_of, per_draw):
        """The sample's surfaces drawn again over the z-buffer its lit pass left, into
        ``framebuffer`` (whose depth is the film's z-buffer), with ``entry`` (a
        ``ProgramPart`` with the entry shader) and ``part_of(tree)`` (the draw's outputs and
        defines for a material's compiled tree, or None): the passes' draws
        (``features/passes.py``). Opaque and alpha-hashed surfaces nearest first, then blended
        ones farthest first, none blended, none writing depth; ``per_draw(shader, draw,
        material)`` sets a draw's own push constants."""
        opaque, blended, submit = self._again(sample)
        submit.masks = None  # the lights are not read
        submit.apart = (entry, part_of)
        submit.per_draw = per_draw
        with self._over_depth(framebuffer):
            submit.draw(opaque, False)
            submit.draw(blended, False, blended=True)
        _reset_state(sample.stats)

    def draw_light(self, sample, framebuffers, part, per_draw=None, masks=None, select=None):
        """The sample's lit pass again over the z-buffer it left, with the frame's techniques'
        parts and ``part`` (a ``ProgramPart`` switching the lit variant to one of Blender's
        light passes, LIGHT_PASS): opaque surfaces (their framebuffer ``framebuffers[0]``) and
        then blended ones blended over them (``framebuffers[1]``), none writing depth;
        ``per_draw(shader, draw, material)`` a draw's own values, ``masks`` {id(draw): light
        mask} the lights each draw takes (a light group's; ``part`` then switches LIGHT_LINKING on);
        ``select(material, blended)``: whether a part is drawn (None: all of them)."""
        opaque, blended, submit = self._again(sample)
        submit.entry = None  # the colour's entry shader, in a debug view's frame too
        if select is not None:
            opaque = [e for e in opaque if select(e[4], False)]
            blended = [e for e in blended if select(e[4], True)]
        if not opaque and not blended:
            return
        submit.light = part
        submit.per_draw = per_draw
        if masks is not None:  # each draw's lights through the light-linking variant
            submit.masks = masks
            submit.variant = dataclasses.replace(sample.data.variant, light_linking=True)
        with self._over_depth(framebuffers[0]):
            submit.draw(opaque, False)
        if blended:
            submit.rebind()
            with self._over_depth(framebuffers[1], "ALPHA_PREMULT"):
                submit.draw(blended, False, blended=True)
        _reset_state(sample.stats)

    def _again(self, sample, hashed_last=False):
        """(opaque entries, blended entries, a ``_Submission``) of the surfaces ``sample``'s lit
        pass drew, to draw them again (``LitPass._entries``)."""
        opaque, blended, parts = self._entries(
            sample.seen, sample.view_camera, sample.atlas, sample.stats, hashed_last=hashed_last
        )
        return opaque, blended, _Submission(self, sample, parts)

    @contextlib.contextmanager
    def _over_depth(self, framebuffer, blend="NONE"):
        """``framebuffer`` bound at the film's size over the z-buffer the lit pass left: tested
        (LESS_EQUAL), not written; ``blend`` while it is bound."""
        import gpu

        width, height = self.film.size
        with framebuffer.bind():
            gpu.state.viewport_set(0, 0, width, height)
            gpu.state.depth_test_set("LESS_EQUAL")
            gpu.state.depth_mask_set(False)
            gpu.state.blend_set(blend)
            yield
            gpu.state.blend_set("NONE")

    def background_into(self, target, frame, sample):
        """What the camera sees of the world where no surface is, into ``target`` (RGBA32F at
        the film's size): the Environment pass's background, whatever the film's transparency."""
        world = frame.snapshot.world
        if world is not None and world.image is not None:
            fb = gpu_framebuffer_with_depth(target, self.film.zbuffer)
            self._background(self.film, world, sample.view_camera, frame.origin, "LESS_EQUAL", fb)
        else:
            color = frame.snapshot.world_color
            target.clear(format="FLOAT", value=(*map(float, color[:3]), 1.0))

    def draw_settle_test(self, sample, target):
        """The settle test's variant of the lit pass (``sample.data`` built for the test) into
        ``target`` (``features.settling.SettleTargets.test_framebuffer``): the surfaces the
        pilot drew (its z-buffer, kept) and any dithered or blended one in front of them write
        their flags, the dithered and blended last, nothing blended."""
        opaque, blended, submit = self._again(sample, hashed_last=True)
        with self._over_depth(target):
            submit.draw(opaque, False)
            if blended:
                submit.rebind()
                submit.draw(blended, False, blended=True)
        _reset_state(sample.stats)

    def end_frame(self):
        """Forget what the frame's samples shared (``_entries``): its draws are not kept past it."""
        self._entries_memo = None

    def _entries(self, draws, camera, atlas, stats, hashed_last):
        """The parts to draw: (opaque and alpha-hashed entries nearest first, blended entries
        farthest first, ``_Parts``); an entry is (features, rank, draw, batch, material).
        ``hashed_last``: alpha-hashed entries after the others (the settle test). Found once
        for a frame's samples: they depend on the draws (a frame's ``Sample.seen``, the same
        list for all of them), the camera's position and near plane (not its pixel offset) and
        whether there are maps."""
        vp_near = camera.projection[2:].tobytes()  # the rows a pixel offset leaves alone
        key = (camera.view.tobytes(), vp_near, bool(camera.is_ortho), atlas is not None, hashed_last)
        memo = self._entries_memo
        if memo is None or memo[0] is not draws or memo[1] != key:
            memo = self._entries_memo = (draws, key, self._find_entries(draws, camera, atlas, hashed_last))
        opaque, blended, parts = memo[2]
        stats.closed_culled += len(parts.outside)
        return list(opaque), list(blended), parts

    @staticmethod
    def _find_entries(draws, camera, atlas, hashed_last):
        """``_entries`` found afresh."""
        # Closed instances wholly beyond the near plane: from there no back face shows.
        outside = set()
        closed = [d for d in draws if d.closed]
        if closed:
            vp = camera.projection @ camera.view
            near = vp[2] + vp[3]  # clip z + w: positive beyond the near plane
            beyond = np.all(np.stack([d.corners for d in closed]) @ near[:3] + near[3] > 0.0, axis=1)
            outside = {id(d) for d, ok in zip(closed, beyond, strict=True) if ok}
        opaque, blended = [], []
        terminators = {}  # id(draw) -> {push constant: value} of its Shadow Terminator features
        for rank, d in enumerate(front_to_back(draws, camera)):
            # Object > Shading > Shadow Terminator: its own variant and, with a geometry
            # offset, the parts carrying the corner data (only when there are shadow maps).
            term = d.terminator_features(atlas is not None)
            parts = d.terminator_parts() if "TERMINATOR_OFFSET" in term else d.parts
            if term:
                terminators[id(d)] = terminator_uniforms(term, d.instance.terminator, d.instance.matrix)
            for mat_index, batch in parts:
                mat = d.material(mat_index)
                features = mat.features | ({"HOLDOUT"} if d.instance.holdout else set()) | term
                if d.instance.hair is not None:
                    features = features | {"HAIR"}
                entry = (features, rank, d, batch, mat)
                (blended if "ALPHA_BLEND" in features and not d.instance.holdout else opaque).append(entry)
        opaque.sort(key=lambda e: (hashed_last and "ALPHA_HASHED" in e[0], sorted(e[0]), e[1]))
        blended.sort(key=lambda e: -e[1])
        return opaque, blended, _Parts(outside, terminators)

    def _background(self, film, world, camera, origin, depth_test="NONE", framebuffer=None):
        """The world's Environment Texture behind the scene (``BACKGROUND``), into the film's
        colour or ``framebuffer``."""
        from mathutils import Matrix

        width, height = film.size
        try:
            inverse = np.linalg.inv(camera.projection @ camera.view @ lightspace.from_origin(origin))
        except np.linalg.LinAlgError:
            return
        if not np.all(np.isfinite(inverse)):
            return
        if world.rotation is not None:  # a Mapping node turns the image: rays in the image's frame
            turn = np.eye(4)
            turn[:3, :3] = world.rotation
            inverse = turn @ inverse
        film.fullscreen(
            BACKGROUND,
            film.fb_color if framebuffer is None else framebuffer,
            {"env": self.textures.get(world.image)},
            {
                "env_premultiplied": float(self.textures.premultiplied(world.image)),
                "inverse_view_proj": Matrix(inverse.tolist()),
                "viewport_origin": (0.0, 0.0),
                "viewport_size": (float(width), float(height)),
                "strength": float(world.strength),
            },
            depth_test=depth_test,
        )

    def _ubo(self, name, data):
        """The block ``name`` holding ``data`` (an array or bytes): sent to the GPU only when
        it holds something else (a lit pass binds its frame and lights blocks to every program
        it switches to, and sends them once)."""
        raw = data if isinstance(data, bytes) else data.tobytes()
        block = self._ubos.holding(name, raw)
        if block is None:
            self.uploaded += len(raw)
            block = self._ubos.get(name, raw)
        return block

    def _jitter(self, samples):
        """The jittered-disk texture: (JITTER_SIZE, JITTER_SIZE, samples / 2) RGBA, two 2-D
        offsets per texel, outer ring first (kernels.jitter_disk); a 1x1x1 texture when the
        variant reads no disk (``samples`` 0)."""
        import gpu

        if samples == 0:
            if self._jitter_dummy is None:
                buf = gpu.types.Buffer("FLOAT", 4, [0.0] * 4)
                self._jitter_dummy = gpu.types.GPUTexture((1, 1, 1), format="RGBA32F", data=buf)
            return self._jitter_dummy
        tex = self._jitter_tex.get(samples)
        if tex is None:
            disk = kernels.jitter_disk(JITTER_SIZE, samples).astype(np.float32)
            # (y, x, sample, 2) -> 3-D texture (x, y, sample pair) of RGBA: z slowest in memory.
            data = disk.reshape(JITTER_SIZE, JITTER_SIZE, samples // 2, 4).transpose(2, 0, 1, 3)
            buf = gpu.types.Buffer("FLOAT", data.size, data.ravel().tolist())
            tex = gpu.types.GPUTexture((JITTER_SIZE, JITTER_SIZE, samples // 2), format="RGBA32F", data=buf)
            self.uploaded += data.nbytes
            self._jitter_tex[samples] = tex
        return tex

    def _bins_texture(self, bins):
        """The light-bin masks as an RGBA32F texture (a 1x1 zero texture when not binned).

        Each channel holds a word of 16 lights as the integer it is (below 2^24, so exact in
        float32, and texelFetch returns a 32-bit float texel unfiltered, exactly as stored on
        any conformant GPU); the shader converts it to uint. An RGBA32UI texture read through
        an unsigned sampler would say so in its type, but Blender's ``gpu.types.GPUTexture``
        takes only FLOAT buffers ("Only Buffer of format `FLOAT` is currently supported",
        4.5 and 5.2), and a float upload into an integer texture is not defined."""
        import gpu

        if bins is None:  # made once
            if self._bins_zero is None:
                zero = gpu.types.Buffer("FLOAT", 4, [0.0] * 4)
                self._bins_zero = gpu.types.GPUTexture((1, 1), format="RGBA32F", data=zero)
                self.uploaded += 16
            return self._bins_zero
        rows, cols = bins.shape[:2]
        buf = gpu.types.Buffer("FLOAT", bins.size, np.ascontiguousarray(bins, np.float32).ravel())
        # Kept until the next frame: the draw that samples it runs after this call returns.
        self._bins_tex = gpu.types.GPUTexture((cols, rows), format="RGBA32F", data=buf)
        self.uploaded += bins.size * 4
        return self._bins_tex

    def _shadow_dummy(self):
        import gpu

        if self._dummy_shadow is None:
            self._dummy_shadow = gpu.types.GPUTexture((1, 1), format="R32F")
            self._dummy_shadow.clear(format="FLOAT", value=(1.0,))
        return self._dummy_shadow


def bind_block(shader, name, block):
    """Bind uniform block ``name`` of ``shader`` where the compiler kept it (a variant that
    reads none of it, an entry shader of the passes', has none: Blender raises there)."""
    try:
        shader.uniform_block(name, block)
    except (BufferError, ValueError):
        pass


def gpu_framebuffer_with_depth(target, zbuffer):
    """A framebuffer drawing into ``target`` over ``zbuffer``."""
    import gpu

    return gpu.types.GPUFrameBuffer(depth_slot=zbuffer, color_slots=(target,))


def set_image_flags(shader, mat, textures):
    """The ``image_premultiplied`` push constant of a draw of ``mat``: which of its images
    Blender stores premultiplied (``programs.image_premultiplied_bits``)."""
    channels = [(channel, ref.image) for channel, ref in mat.textures.items()]
    tree_images = [ref.image for ref in mat.tree.images] if mat.tree is not None else []
    set_uniforms(
        shader, {"image_premultiplied": image_premultiplied_bits(textures.premultiplied, channels, tree_images)}
    )


def object_thickness(corners):
    """The smallest dimension of an instance's bounds from their world ``corners`` (8, 3; corner
    i at bits x, y, z of i): what a transmissive surface takes for its thickness (EEVEE's
    default); 0 for a flat one (a pane: light crosses one interface)."""
    c = np.asarray(corners, np.float64)
    dims = [np.linalg.norm(c[k] - c[0]) for k in (1, 2, 4)]
    thickness = float(min(dims))
    return thickness if np.isfinite(thickness) and thickness > 0.0 else 0.0


@dataclass
class _Parts:
    """What ``LitPass._entries`` found of the draws: closed instances whose back faces never
    show (``outside``, by id) and each draw's Shadow Terminator uniforms."""

    outside: set
    terminators: dict


def _reset_state(stats):
    """The GPU state a lit pass leaves as it found it; one pass more in ``stats``."""
    import gpu

    gpu.state.face_culling_set("NONE")
    gpu.state.front_facing_set(False)
    gpu.state.depth_test_set("NONE")
    gpu.state.depth_mask_set(False)
    stats.passes += 1


class _Submission:
    """One lit pass's draw calls: each entry's program bound once while it stays the same, its
    frame, light and tile blocks, its maps and textures, its per-object push constants.
    ``emission`` and ``counted``: what the film's targets take (the settle test's take none
    of them); ``rebind()`` before drawing into other targets."""

    def __init__(self, lit, sample, parts):
        atlas, data = sample.atlas, sample.data
        self.lit, self.data, self.atlas, self.origin = lit, data, atlas, sample.origin
        self.masks, self.parts, self.stats = sample.masks, parts, sample.stats
        self.mirrored = bool(sample.mirrored)  # a mirrored view turns every winding (``features/planar.py``)
        self.shadow_tex = atlas.texture if atlas is not None else lit._shadow_dummy()
        self.emission = self.counted = False
        self.apart = None  # (entry part, part of a tree): a draw apart (``LitPass.draw_apart``)
        self.light = None  # a light pass's part after the techniques' (``LitPass.draw_light``)
        self.variant = data.variant  # the lit variant its draws take
        # What every program it binds reads, made and sent once.
        self.frame_bytes, self.lights_bytes = data.frame.tobytes(), data.lights.tobytes()
        self.jitter_tex, self.bins_tex = lit._jitter(data.disk_samples), lit._bins_texture(data.bins)
        self.per_draw = None
        # A debug view's entry shader, unless a technique's part brings its own (the settle test's).
        variant = data.variant
        debug = (variant.debug or variant.debug_term) and not any(p.fragment for p in data.parts)
        self.entry = ENTRY_PARTS["debug"] if debug else None
        # The sample's tile records: the instanced depth pass's block when it holds them.
        tiles = atlas.tiles_block(data.tiles) if atlas is not None else None
        self.tiles = tiles if tiles is not None else lit._ubo("tiles", data.tiles)
        # Strand-shaped hair: half a pixel's width per unit of clip w (the camera's y scale).
        camera = sample.view_camera
        self.hair_pixel = 1.0 / max(abs(float(camera.projection[1, 1])) * lit.film.size[1], 1e-30)
        self.shader = self.model_shader = self.culling = None
        self.solid = {}
        self._shaders = {}  # what a draw binds -> its compiled program (``key``)

    def rebind(self, counted=None):
        """Bind afresh at the next draw (other targets); ``counted``: whether they count."""
        self.shader = None
        if counted is not None:
            self.counted = counted

    def key(self, features, with_aux, tree, blended=False, emission_only=False):
        """The ``programs.LitKey`` of a draw: the pass's targets, the frame's techniques' parts
        (``blended``: those blended surfaces take), the material's, and the entry shader."""
        data = self.data
        if self.apart is not None:  # a draw of its own: its part and entry, nothing of the techniques'
            entry, part_of = self.apart
            return lit_key(False, data.variant, (part_of(tree),), features, tree, entry)
        if emission_only:  # what the surface emits, nothing of the techniques'
            return lit_key(False, data.variant, (EMISSION_ONLY,), features, tree)
        own = (EMISSION_PART,) if self.emission and with_aux else ()
        own += (COUNTED_PART,) if self.counted and not with_aux else ()
        techniques = data.blended_parts if blended else data.parts
        if self.light is not None:
            techniques = (*techniques, self.light)
        return lit_key(with_aux, self.variant, own + techniques, features, tree, self.entry)

    def bind(self, features, with_aux, tree, blended=False, emission_only=False):
        lit, data = self.lit, self.data
        which = (features, with_aux, id(tree), blended, emission_only, self.emission, self.counted)
        shader = self._shaders.get(which)
        if shader is None:
            key = self.key(features, with_aux, tree, blended, emission_only)
            shader = self._shaders[which] = lit.shaders.get(key.program(), key.defines())
            self.stats.lit_keys.add(key)
        if self.shader is shader:
            return shader
        if tree is not None and "ORIGIN" in tree.needs:
            shader.bind()
            shader.uniform_float("node_origin", tuple(float(x) for x in self.origin))
        shader.bind()
        shader.uniform_block("frame", lit._ubo("frame", self.frame_bytes))
        shader.uniform_block("lights", lit._ubo("lights", self.lights_bytes))
        shader.uniform_block("shadow_tiles", self.tiles)
        shader.uniform_sampler(SHADOW_SAMPLER, self.shadow_tex)
        shader.uniform_sampler("jitter_tex", self.jitter_tex)
        shader.uniform_sampler("light_bins", self.bins_tex)
        for name, texture in data.samplers.items():  # the techniques' (``LitPart.samplers``)
            shader.uniform_sampler(name, texture)
        for name, raw in data.blocks.items():  # the techniques' (``LitPart.blocks``)
            bind_block(shader, name, lit._ubo(name, raw))
        self.shader = shader
        return shader

    def _has(self, shader, name):
        """Whether ``shader`` kept the push constant ``name`` (the compiler removes unread ones)."""
        key = (shader, name)
        if key not in self.solid:
            try:
                self.solid[key] = shader.uniform_from_name(name) != -1
            except ValueError:  # Blender raises where GL reports -1
                self.solid[key] = False
        return self.solid[key]

    def draw(self, entries, with_aux, blended=False, emission_only=False):
        import gpu

        lit, outside, terminators = self.lit, self.parts.outside, self.parts.terminators
        last = None
        for features, _rank, d, batch, mat in entries:
            # Material › Backface Culling › Camera: faces turned away are not drawn (the
            # winding flips under a mirroring model matrix, and again through a mirrored view).
            cull = (mat.cull_camera or id(d) in outside) and d.instance.hair is None  # strips have no back
            culling = (cull, cull and (d.det < 0.0) != self.mirrored)
            if self.culling != culling:
                gpu.state.face_culling_set("BACK" if culling[0] else "NONE")
                gpu.state.front_facing_set(culling[1])
                self.culling = culling
            shader = self.bind(features, with_aux, mat.tree, blended, emission_only)
            if last is not d or self.model_shader is not shader:
                shader.uniform_float("model", d.model)
                if self._has(shader, "solid"):  # compiled out where no light reads it
                    shader.uniform_int("solid", int(id(d) in outside))
                if self.masks is not None:
                    shader.uniform_int("light_mask", self.masks[id(d)])
                if id(d) in terminators:  # skipping any the compiler removed (a holdout's)
                    set_uniforms(shader, terminators[id(d)])
                if TRANSMISSION in features and self._has(shader, "object_thickness"):
                    shader.uniform_float("object_thickness", object_thickness(d.corners))
                if d.instance.hair is not None:
                    shader.uniform_float("hair_pixel", self.hair_pixel if d.instance.hair == "STRAND" else 0.0)
                last, self.model_shader = d, shader
            if self.per_draw is not None:
                self.per_draw(shader, d, mat)
            if mat.tree is not None and mat.tree.needs & {"GENERATED", "OBJECT_INFO"}:
                set_uniforms(shader, d.tree_uniforms(mat.tree))
            shader.uniform_block("material", lit.materials.get(mat))
            for channel, ref in mat.textures.items():
                shader.uniform_sampler(f"tex_{channel}", lit.textures.get(ref.image))
            if mat.tree is not None:
                shader.uniform_block("node_constants", lit.materials.constants(mat))
                for i, ref in enumerate(mat.tree.images):
                    shader.uniform_sampler(f"node_image_{i}", lit.textures.get(ref.image))
            if mat.textures or (mat.tree is not None and mat.tree.images):
                set_image_flags(shader, mat, lit.textures)
            batch.draw(shader)
            self.stats.draws += 1
