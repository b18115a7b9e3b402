"""The film: a frame's render targets (colour, and the passes' depth, shadow, normal and
emission), the float32 accumulation of its samples and their resolve into the filtered
average, and read-back to numpy. Targets come from the engine's ``gpu_pool.TexturePool`` in
final renders and go back to it on ``release``."""

from dataclasses import dataclass

import numpy as np

from ..gpu_pool import new_texture
from ..post.base import PostContext
from .film_programs import (
    CONVERGED_DEPTH,
    MASKED_COPY,
    MASKED_COPY_SHADOW_WEIGHT,
    MASKED_COPY_WEIGHT,
    MAX_TARGETS,
    SCALED_COPY,
    SCALED_COPY_SHADOW,
    SCALED_RESOLVE_SHADOW,
    WEIGHTED_RESOLVE,
    WEIGHTED_RESOLVE_SHADOW,
    convergence_program,
    gathering,
    with_copies,
)
from .sampling import THRESHOLD_SCALE
from .stats import StageClock


@dataclass
class FrameOutput:
    color: object  # GPUTexture, scene-linear RGBA float
    depth: object  # GPUTexture RGBA: w the view-space distance along the camera axis (the normal target)
    shadow: object  # GPUTexture, fraction of direct light not blocked (1 for background)
    stats: object  # stats.FrameStats
    width: int
    height: int
    lit: object = None  # GPUTexture, the lit pass before the post stack
    normal: object = None  # GPUTexture, world-space shading normal (0 for the background)
    depth_data: object = None  # arrays of the centred sample when several were accumulated
    normal_data: object = None
    emission: object = None  # GPUTexture, the Emission pass (when asked for)
    debug: object = None  # debug_view.DebugImage when a debug view replaced the image
    # Blender's further passes (``features/passes.py``): {key: GPUTexture, or the Cryptomatte
    # ``cryptomatte.Accumulator``}
    passes: dict = None

    def pass_array(self, key, channels):
        """A further pass's pixels (height, width, ``channels``); Position in the world's
        frame (drawn relative to the frame origin; 0 where no surface is)."""
        data = texture_array(self.passes[key], 4)
        if key == "POSITION":
            hit = data[..., 3:4] > 0.0
            origin = np.asarray(self.passes.get("ORIGIN", (0.0, 0.0, 0.0)), np.float64)
            return np.where(hit, data[..., :3] + origin, 0.0).astype(np.float32)
        return data[..., :channels]

    def emission_array(self):
        return texture_array(self.emission, 4)[..., :3]

    def normal_array(self):
        if self.normal_data is not None:
            return self.normal_data[..., :3]
        return texture_array(self.normal, 4)[..., :3]

    def lit_array(self):
        return texture_array(self.lit, 4)

    def color_array(self):
        return texture_array(self.color, 4)

    def depth_array(self):
        if self.depth_data is not None:
            return self.depth_data
        return texture_array(self.depth, 4)[..., 3]

    def shadow_array(self):
        return texture_array(self.shadow, 1)[..., 0]


class FilmPart:
    """A technique's targets in the film (``features.Feature.film_part``): what it keeps per
    sample and accumulates beside the colour, and how it takes part in each of the film's
    steps. ``lit_targets``: how many colour targets the lit pass writes for it after the
    pass's own (its ``ProgramPart``'s outputs; 0: none). Every hook does nothing by default.

    The film calls, for the parts of the frame (``Film.begin``): ``framebuffer`` (the lit
    pass's targets with its own), ``clear`` (before a sample's lit pass), ``begin`` (a fresh
    frame), ``copies`` (what each sample adds to its accumulations), ``accumulated`` (what a
    sample's value kept copies), ``convergence``
    (its share of the convergence check), ``resolve`` (after the last sample, into the colour
    target; or into ``framebuffer``, ``Film.mean_into``: the mean so far, over the film's),
    ``resolve_light`` (a light pass's resolve, where the part takes light out of the colour's),
    ``bytes_per_pixel``, and ``release`` whenever the film's targets go (a new size, the end
    of a render)."""

    name = ""
    lit_targets = 0
    # Its ``resolve`` writes every pixel of the colour from the accumulation itself (not over
    # the plain average): ``Film.mean_into`` then draws no plain average first.
    resolves_colour = False

    def framebuffer(self, film, slots, blended=False):
        raise NotImplementedError(f"{self.name}: no targets of its own in the lit pass")

    def clear(self, film):
        pass

    def begin(self, film):
        pass

    def copies(self, film, sample):
        """(this sample's target, its accumulation) pairs ``Film.accumulate`` adds to with the
        sample's weight, in its passes (``sample``: the index; adaptive sampling tracks odd ones)."""
        return ()

    def accumulated(self, film):
        """(accumulation, this sample's target) pairs: where a technique that keeps one
        sample's value in the pixels it converges (settling's pilot) copies that value."""
        return ()

    def convergence(self, film):
        """(``ProgramPart`` of the convergence check, {sampler: texture}), or None."""
        return None

    def resolve(self, film, framebuffer=None):
        pass

    def resolve_light(self, film, source, framebuffer, lobes, scratch):
        """Resolve ``source`` (a light pass's accumulation carrying the world's light of
        ``lobes``, (diffuse, specular)) into ``framebuffer`` as the colour's resolve treats that
        light; ``scratch``: a texture at the film's size it may overwrite. Returns whether it
        did (False: the plain average is the pass's)."""
        return False

    def bytes_per_pixel(self, film):
        return 0

    def release(self, film):
        pass


def gathered(program, gather, reach):
    """``program``, or, when ``gather`` is given, its variant gathering ``reach`` pixels each way."""
    return gathering(program, reach) if gather else program


def clear_zero(texture):
    """``texture`` (RGBA or RG float) cleared to 0 in every channel."""
    texture.clear(format="FLOAT", value=(0.0, 0.0) if texture.format == "RG32F" else (0.0, 0.0, 0.0, 0.0))


def gpu_framebuffer(texture):
    """A framebuffer drawing into ``texture`` alone."""
    import gpu

    return gpu.types.GPUFrameBuffer(color_slots=(texture,))


def buffer_array(buf):
    """A ``gpu.types.Buffer`` as a C-ordered numpy array of its dimensions.

    Blender 4.5's buffer protocol reports reversed strides, so ``np.asarray`` alone scrambles
    multi-dimensional data there; reading the memory in its own order is right on every line."""
    a = np.asarray(buf)
    return a.ravel(order="K").reshape(tuple(buf.dimensions))


def texture_array(texture, channels):
    """Read a float texture back as an array (height, width, channels), row 0 at the bottom."""
    return buffer_array(texture.read()).astype(np.float32, copy=False).reshape(texture.height, texture.width, channels)


class Film:
    """The targets of one renderer at the frame's size. The lit pass draws into ``fb_color``
    (colour and z-buffer), ``fb`` (with the depth, shadow and normal passes) or ``fb_emit``
    (with Emission too); a multi-sample frame adds each sample into the accumulation targets
    (``accumulate``) and ``resolve`` writes their filtered average back into ``color`` (and
    ``shadow``), which the post stack and the passes then read as a single sample's.

    Adaptive sampling (``begin(..., adaptive=True)``): every other sample is also added, twice
    over, to a second accumulation; ``check`` compares the two per pixel on the GPU and marks
    converged pixels in a mask (``mask``). Once a pixel converged, later samples add nothing to
    it (``accumulate`` writes through the mask, with each pixel's own weight in a weight
    target), the lit pass does not shade it (``mask_depth``) and ``resolve`` divides by each
    pixel's weight. Until then every step is the plain accumulation's, to the bit.

    A technique's targets (``FilmPart``, ``begin(..., parts=...)``: the world ratio's) take part
    in each of these steps through the part's hooks; the film does not name them."""

    def __init__(self, shaders, pool=None):
        self.shaders = shaders
        self.pool = pool
        self.size = None
        self.color = self.zbuffer = self.depth = self.shadow = self.normal = self.emission = None
        self.fb = self.fb_color = self.fb_emit = None
        self.post_ctx = None  # the post stack's targets at this size
        self.clock = StageClock()  # the frame's (``Renderer.render``): read-backs count as GPU time
        self.centre = None  # (depth, normal) arrays of a multi-sample frame's centred sample
        self._accum_color = self._accum_shadow = self._accum_fb = self._resolve_fb = None
        self._emission_targets = None  # (accumulation, its framebuffer, the resolve's framebuffer)
        self._weight_sum = 0.0
        self._half_weight_sum = 0.0
        self.gather_reach = 0  # the frame's (``begin``)
        self.sample_weights = []  # each accumulated sample's filter weight, in order
        self._fullscreen_batch = None
        # Adaptive sampling: the every-other-sample accumulation, the converged masks (read
        # one, write the other), each pixel's weight once some pixel converged.
        self.tracking = False
        self.converged = 0  # pixels converged (no more samples)
        self._half = None
        self._masks = self._mask_fbs = None
        self._mask_index = 0
        self._weight = None
        self._copy_fbs = {}
        # The shading count of tests (``count_shaded``): the lit pass writes 1 into ``shaded``
        # for every pixel it shades; ``shaded_total`` adds them over the frame's samples.
        self.count_shaded = False
        self.shaded = self.fb_counted = self.shaded_total = self._shaded_total_fb = None
        # The techniques' targets (``FilmPart``): the frame's, and every part the film has met
        # (each gives its targets back with the film's).
        self.parts = ()
        self._known_parts = []
        self._emission_fb = None

    # --- targets --------------------------------------------------------------------------

    def ensure(self, width, height, aux, emission=False):
        """The lit pass's targets at this size; the auxiliary ones (depth, shadow, normal) only
        once a frame asks for them, the Emission pass's likewise."""
        import gpu

        if self.size != (width, height):
            self._give_targets()
            self.color = new_texture(self.pool, (width, height), "RGBA32F")
            self.zbuffer = new_texture(self.pool, (width, height), "DEPTH_COMPONENT32F")
            self.fb_color = gpu.types.GPUFrameBuffer(depth_slot=self.zbuffer, color_slots=(self.color,))
            if self.post_ctx is not None:
                self.post_ctx.release()
            self.post_ctx = PostContext(self.shaders, width, height, texture_pool=self.pool)
            self.size = (width, height)
        if aux and self.fb is None:
            # The normal target carries the view depth in w (Blender's gpu module binds at most
            # six colour targets: a technique's targets need the room).
            self.shadow = new_texture(self.pool, (width, height), "R32F")
            self.normal = new_texture(self.pool, (width, height), "RGBA32F")
            self.depth = self.normal
            self.fb = gpu.types.GPUFrameBuffer(
                depth_slot=self.zbuffer, color_slots=(self.color, self.shadow, self.normal)
            )
        if self.count_shaded and self.fb_counted is None:
            self.shaded = new_texture(self.pool, (width, height), "R32F")
            self.fb_counted = gpu.types.GPUFrameBuffer(depth_slot=self.zbuffer, color_slots=(self.color, self.shaded))
            self.shaded_total = new_texture(self.pool, (width, height), "R32F")
            self.shaded_total.clear(format="FLOAT", value=(0.0,))
            self._shaded_total_fb = gpu.types.GPUFrameBuffer(color_slots=(self.shaded_total,))
        if emission and self.fb_emit is None:
            self.emission = new_texture(self.pool, (width, height), "RGBA32F")
            self.fb_emit = gpu.types.GPUFrameBuffer(
                depth_slot=self.zbuffer,
                color_slots=(self.color, self.shadow, self.normal, self.emission),
            )

    @property
    def lit_part(self):
        """The frame's part whose targets the lit pass writes beside its own (at most one:
        Blender's gpu module binds six colour targets), or None."""
        return next((p for p in self.parts if p.lit_targets), None)

    def lit_framebuffer(self, aux, emission, counted, part=None):
        """The lit pass's framebuffer: colour and z-buffer, with ``aux`` the depth, shadow and
        normal passes, with ``emission`` the Emission pass, ``counted`` (colour only) the
        shading count; ``part``: then that ``FilmPart``'s targets."""
        fb = self.fb_emit if emission else (self.fb if aux else (self.fb_counted if counted else self.fb_color))
        if part is None:
            return fb
        if emission:
            slots = (self.color, self.shadow, self.normal, self.emission)
        elif aux:
            slots = (self.color, self.shadow, self.normal)
        else:
            slots = (self.color, self.shaded) if counted else (self.color,)
        return part.framebuffer(self, slots)

    def emission_framebuffer(self):
        """The Emission pass's target over the z-buffer (its own draw: ``LitPass.draw``)."""
        import gpu

        if self._emission_fb is None:
            self._emission_fb = gpu.types.GPUFrameBuffer(depth_slot=self.zbuffer, color_slots=(self.emission,))
        return self._emission_fb

    def blend_framebuffer(self, part=None):
        """The framebuffer blended surfaces draw into: colour, and with ``part`` that
        ``FilmPart``'s targets they write (the world ratio's SH light, which they attenuate)."""
        return self.fb_color if part is None else part.framebuffer(self, (self.color,), blended=True)

    def clear(self, background, aux, emission, part=None):
        """Every target the lit pass writes, cleared to what the background is: ``background``
        colour (premultiplied), and for the passes an "infinitely" far depth (as Blender's own
        Depth pass), full light, no normal, no emission."""
        self.color.clear(format="FLOAT", value=background)
        if aux:
            self.shadow.clear(format="FLOAT", value=(1.0,))
            self.normal.clear(format="FLOAT", value=(0.0, 0.0, 0.0, 1e10))
        if emission:
            self.emission.clear(format="FLOAT", value=(0.0, 0.0, 0.0, 0.0))
        if self.shaded is not None:
            self.shaded.clear(format="FLOAT", value=(0.0,))
        if part is not None:
            part.clear(self)

    def target_bytes(self, aux, accumulate):
        """Bytes per pixel of the frame's targets: colour, z-buffer, and with ``aux`` depth,
        shadow and normal; accumulation adds colour (and shadow); adaptive sampling its second
        accumulation, two masks and, once some pixel converged, the weights."""
        per_pixel = 16 + 4 + (4 + 16 if aux else 0)
        if accumulate:
            per_pixel += 16 + (4 if aux else 0)
            if self.tracking:
                per_pixel += 16
            if self._masks is not None:
                per_pixel += 4 + 4 + (8 if self._weight is not None else 0)
            per_pixel += sum(part.bytes_per_pixel(self) for part in self.parts)
        return per_pixel * self.size[0] * self.size[1]

    # --- samples --------------------------------------------------------------------------

    def begin(self, aux, emission, fresh, adaptive=False, masks=False, parts=(), gather_reach=0):
        """Before a multi-sample frame's samples: the accumulation targets, cleared when the
        frame starts afresh (``fresh``); ``adaptive``: the frame estimates each pixel's error
        (from a fresh start on); ``masks``: a technique converges pixels (``update_mask``), so the converged
        masks exist; ``parts``: the techniques' targets (``FilmPart``);
        ``gather_reach``: the gathering film's reach in pixels (``sampling.gather_reach``; 0:
        each pixel its own samples), which a converged pixel stays shaded for."""
        self.gather_reach = int(gather_reach)
        self._ensure_accumulation(aux)
        self.parts = tuple(parts)
        self._known_parts += [p for p in self.parts if p not in self._known_parts]
        if fresh:
            self._begin_adaptive(adaptive, masks)
            for part in self.parts:
                part.begin(self)
            if self.shaded_total is not None:
                self.shaded_total.clear(format="FLOAT", value=(0.0,))
            self._accum_color.clear(format="FLOAT", value=(0.0, 0.0, 0.0, 0.0))
            if self._accum_shadow is not None:
                self._accum_shadow.clear(format="FLOAT", value=(0.0,))
            if emission:
                self._emission_accumulation().clear(format="FLOAT", value=(0.0, 0.0, 0.0, 0.0))
            self._weight_sum = 0.0
            self._half_weight_sum = 0.0  # of the every-other-sample accumulation (the odd samples)
            self.sample_weights = []

    def accumulate(self, weight, aux, emission, sample=0, gather=None):
        """accumulation += weight * this sample (colour, shadow with ``aux``, and Emission),
        in the pixels that have not converged; ``sample``: its index (adaptive sampling adds
        the odd ones to its second accumulation). ``gather`` (``sampling.gather_uniforms``):
        each pixel takes the sample from the pixels within the filter's reach, by the window's
        weights, which sum to ``weight`` (the gathering film).

        Every accumulation a sample adds to takes the same weight, mask and gathering: the
        colour's pass carries the others (the Emission pass, the every-other-sample
        accumulation, the techniques' ``FilmPart.copies``) in the targets Blender's gpu module
        has left (six in all), and those that do not fit go six to a pass. Each target gains
        exactly what a pass of its own would add."""
        mask = self.mask
        copies = []
        if emission:
            copies.append((self.emission, self._emission_targets[0]))
        if self.tracking and sample % 2 == 1:
            copies.append((self.color, self._half))
            self._half_weight_sum += weight
        for part in self.parts:
            copies.extend(part.copies(self, sample))
        with_shadow = aux and self._accum_shadow is not None
        samplers = {"src_color": self.color}
        if with_shadow:
            samplers["src_shadow"] = self.shadow
        if mask is None:
            program = SCALED_COPY_SHADOW if with_shadow else SCALED_COPY
            slots = (self._accum_color, self._accum_shadow) if with_shadow else (self._accum_color,)
        else:
            samplers["converged"] = mask
            program = MASKED_COPY_SHADOW_WEIGHT if with_shadow else MASKED_COPY_WEIGHT
            slots = (
                (self._accum_color, self._accum_shadow, self._weight)
                if with_shadow
                else (self._accum_color, self._weight)
            )
        riding = copies[: MAX_TARGETS - len(slots)]
        self._add_copies(program, slots, samplers, riding, weight, gather)
        rest = copies[len(riding) :]
        for k in range(0, len(rest), MAX_TARGETS):  # what did not fit: six a pass
            (source, target), *more = rest[k : k + MAX_TARGETS]
            alone = {"src_color": source} if mask is None else {"src_color": source, "converged": mask}
            self._add_copies(SCALED_COPY if mask is None else MASKED_COPY, (target,), alone, more, weight, gather)
        if self._shaded_total_fb is not None:
            self.fullscreen(
                SCALED_COPY, self._shaded_total_fb, {"src_color": self.shaded}, {"scale": 1.0}, "ADDITIVE_PREMULT"
            )
        self._weight_sum += weight
        self.sample_weights.append(float(weight))

    def _add_copies(self, program, slots, samplers, copies, weight, gather):
        """One pass of ``program`` adding ``weight`` times its sources into ``slots``, and each
        of ``copies`` ((source, accumulation) pairs) likewise (``film_programs.with_copies``)."""
        samplers = {**samplers, **{f"src_copy{k}": source for k, (source, _target) in enumerate(copies)}}
        framebuffer = self._copies_framebuffer((*slots, *(target for _source, target in copies)))
        program = gathered(with_copies(program, len(copies)), gather, self.gather_reach)
        self.fullscreen(program, framebuffer, samplers, {"scale": weight, **(gather or {})}, "ADDITIVE_PREMULT")

    def _copies_framebuffer(self, slots):
        """A framebuffer of the colour targets ``slots``, kept while the film keeps its targets
        (it holds them, so an entry never stands for other textures)."""
        import gpu

        key = tuple(id(t) for t in slots)
        found = self._copy_fbs.get(key)
        if found is None or any(a is not b for a, b in zip(found[0], slots, strict=True)):
            if len(self._copy_fbs) >= 32:
                self._copy_fbs.clear()
            found = self._copy_fbs[key] = (tuple(slots), gpu.types.GPUFrameBuffer(color_slots=tuple(slots)))
        return found[1]

    def copy(self, framebuffer, source, scale, mask, gather=None):
        """framebuffer += scale * source, where not converged (``mask``, when some pixel is);
        ``gather``: the source gathered over the filter's reach."""
        uniforms = {"scale": scale, **(gather or {})}
        if mask is None:
            program = gathered(SCALED_COPY, gather, self.gather_reach)
            self.fullscreen(program, framebuffer, {"src_color": source}, uniforms, "ADDITIVE_PREMULT")
        else:
            samplers = {"src_color": source, "converged": mask}
            self.fullscreen(
                gathered(MASKED_COPY, gather, self.gather_reach),
                framebuffer,
                samplers,
                uniforms,
                "ADDITIVE_PREMULT",
            )

    def keep_centre(self):
        """Keep the centred sample's depth and normal (a multi-sample frame's Depth and Normal
        passes are that sample's, not an average)."""
        with self.clock.waiting():
            normal = texture_array(self.normal, 4).copy()
            self.centre = (normal[..., 3].copy(), normal)

    def resolve(self, aux, emission):
        """The filtered average (accumulation / total weight) into the colour (and shadow,
        Emission) targets, which the post stack and the passes read as a single-sample frame's."""
        import gpu

        with_shadow = aux and self._accum_shadow is not None
        if self._resolve_fb is None or self._resolve_fb[0] != (self.size, with_shadow):
            slots = (self.color, self.shadow) if with_shadow else (self.color,)
            self._resolve_fb = ((self.size, with_shadow), gpu.types.GPUFrameBuffer(color_slots=slots))
        if self._weight is not None:  # pixels hold different numbers of samples
            samplers = {"src_color": self._accum_color, "weight": self._weight}
            if with_shadow:
                samplers["src_shadow"] = self._accum_shadow
            program = WEIGHTED_RESOLVE_SHADOW if with_shadow else WEIGHTED_RESOLVE
            self.fullscreen(program, self._resolve_fb[1], samplers, {})
            if emission:
                accum, _accum_fb, resolve_fb = self._emission_targets
                self.fullscreen(WEIGHTED_RESOLVE, resolve_fb, {"src_color": accum, "weight": self._weight}, {})
        else:
            inverse = 1.0 / self._weight_sum if self._weight_sum > 0.0 else 0.0
            self._scaled_copy(self._resolve_fb[1], (self._accum_color, self._accum_shadow), inverse, aux, resolve=True)
            if emission:
                accum, _accum_fb, resolve_fb = self._emission_targets
                self.fullscreen(SCALED_COPY, resolve_fb, {"src_color": accum}, {"scale": inverse})
        for part in self.parts:
            part.resolve(self)

    def mean_into(self, framebuffer):
        """The colour's mean over the samples accumulated so far (what ``resolve`` would write,
        the techniques' parts' included) into ``framebuffer`` (one RGBA32F target at the
        film's size), leaving the film's own targets as they are: what a later sample reads of
        the frame's image (``features/reflections.py``). A part that resolves the whole colour
        itself (``FilmPart.resolves_colour``: the world's ratio) writes it alone."""
        if not any(part.resolves_colour for part in self.parts):
            if self._weight is not None:
                samplers = {"src_color": self._accum_color, "weight": self._weight}
                self.fullscreen(WEIGHTED_RESOLVE, framebuffer, samplers, {})
            else:
                inverse = 1.0 / self._weight_sum if self._weight_sum > 0.0 else 0.0
                self.fullscreen(SCALED_COPY, framebuffer, {"src_color": self._accum_color}, {"scale": inverse})
        for part in self.parts:
            part.resolve(self, framebuffer)

    @property
    def accum_color(self):
        """The colour's accumulation (weighted sum of the samples)."""
        return self._accum_color

    @property
    def weight(self):
        """Each pixel's weight (RG32F: its samples' total weight, their count) once pixels hold
        different numbers of samples; None while every pixel has them all (``weight_sum``)."""
        return self._weight

    @property
    def weight_sum(self):
        """The total weight of the samples accumulated so far."""
        return self._weight_sum

    # --- adaptive sampling ----------------------------------------------------------------

    @property
    def mask(self):
        """The converged mask (R32F, 1 where a pixel converged), or None while no pixel has."""
        return self._masks[self._mask_index] if self.converged and self._masks is not None else None

    def _begin_adaptive(self, adaptive, masks=False):
        """A fresh frame: no pixel converged; with ``adaptive`` the second accumulation, with
        it or ``masks`` the masks exist (at this size) and are cleared."""
        import gpu

        self.tracking = bool(adaptive)
        self.converged = 0
        self.give([self._weight])
        self._weight = None
        self._copy_fbs = {}
        if not (self.tracking or masks):
            return
        size = self.size
        if self._masks is None or (self._masks[0].width, self._masks[0].height) != size:
            self.give([self._half, *(self._masks or ())])
            self._half = None
            self._masks = [new_texture(self.pool, size, "R32F") for _ in range(2)]
            self._mask_fbs = [gpu.types.GPUFrameBuffer(color_slots=(m,)) for m in self._masks]
        if self.tracking and self._half is None:
            self._half = new_texture(self.pool, size, "RGBA32F")
        if self.tracking:
            self._half.clear(format="FLOAT", value=(0.0, 0.0, 0.0, 0.0))
        for m in self._masks:
            m.clear(format="FLOAT", value=(0.0,))
        self._mask_index = 0

    def update_mask(self, program, samplers, uniforms):
        """One pass of ``program`` from the converged mask (its sampler ``converged``) into the
        other mask, which becomes the converged mask (a technique's test: settling's); returns
        the number of converged pixels."""
        src, dst = self._mask_index, 1 - self._mask_index
        self.fullscreen(program, self._mask_fbs[dst], {**samplers, "converged": self._masks[src]}, uniforms)
        return self._take_mask(dst)

    def accumulations(self, aux, emission):
        """{target: (its accumulation, this sample's)} of the colour, and of the Shadow pass
        (``aux``, once accumulated) and the Emission pass (``emission``) where the frame has them."""
        out = {"color": (self._accum_color, self.color)}
        if aux and self._accum_shadow is not None:
            out["shadow"] = (self._accum_shadow, self.shadow)
        if emission and self._emission_targets is not None:
            out["emission"] = (self._emission_targets[0], self.emission)
        return out

    def check(self, threshold):
        """The convergence check after an even number of samples: a pixel converges when the
        error estimate of its 3x3 neighbourhood is below ``threshold`` (Cycles' Noise
        Threshold); once converged it stays so. Returns the number of converged pixels."""

        src, dst = self._mask_index, 1 - self._mask_index
        samplers = {
            "accum": self._accum_color,
            "half_accum": self._half,
            "converged": self._masks[src],
            "weight": self._weight if self._weight is not None else self._masks[src],
        }
        uniforms = {
            "threshold": float(threshold) * THRESHOLD_SCALE,
            "weight_sum": float(self._weight_sum),
            "per_pixel": 1.0 if self._weight is not None else 0.0,
            "half_scale": self._half_scale(),
        }
        self.fullscreen(self._convergence(False, samplers), self._mask_fbs[dst], samplers, uniforms)
        return self._take_mask(dst)

    def _half_scale(self):
        """What the every-other-sample accumulation is multiplied by to be a mean over the
        same weight as the whole one: the total weight over the odd samples' (2 when the
        samples weigh alike; a gathering film's samples do not)."""
        return float(self._weight_sum / self._half_weight_sum) if self._half_weight_sum > 0.0 else 2.0

    def _convergence(self, error_output, samplers):
        """The convergence check's program with the frame's parts' shares of it (adding their
        samplers to ``samplers``)."""
        shares = [share for share in (part.convergence(self) for part in self.parts) if share is not None]
        for _part, more in shares:
            samplers.update(more)
        return convergence_program(error_output, tuple(part for part, _more in shares))

    def _take_mask(self, dst):
        """Mask ``dst`` becomes the converged mask; returns its count (and from the first
        converged pixel on, each pixel keeps its own weight)."""
        self._mask_index = dst
        with self.clock.waiting():
            mask = texture_array(self._masks[dst], 1)
        count = int(np.count_nonzero(mask > 0.5))
        if count and self._weight is None:
            # From now on pixels hold different numbers of samples; so far each has them all.
            # r: the pixel's weight; g: the samples it took (a gathering film's pixel may take
            # less than a sample's whole weight, beside a converged one).
            self._weight = new_texture(self.pool, self.size, "RG32F")
            self._weight.clear(format="FLOAT", value=(float(self._weight_sum), float(len(self.sample_weights))))
            self._copy_fbs = {}
        self.converged = count
        return count

    def finish(self):
        """Wait until the GPU has drawn everything asked so far (one pixel read back)."""
        with self._accum_fb.bind(), self.clock.waiting():
            self._accum_fb.read_color(0, 0, 1, 1, 4, 0, "FLOAT")

    def weights_array(self):
        """Each pixel's weight (its samples' total), (height, width)."""
        if self._weight is None:
            return np.full(self.size[::-1], self._weight_sum, np.float32)
        return texture_array(self._weight, 2)[..., 0]

    def samples_array(self):
        """Samples each pixel took, (height, width): every sample so far until a pixel
        converged, then what it had (counted beside its weight)."""
        if self._weight is None:
            return np.full(self.size[::-1], len(self.sample_weights), np.float32)
        return texture_array(self._weight, 2)[..., 1].copy()

    def error_array(self):
        """Each pixel's error estimate as adaptive sampling's check reads it (the largest of its
        3x3 neighbourhood), in units of the Noise Threshold, (height, width); None when the
        frame did not track it (a frame without adaptive sampling, or one sample)."""
        import gpu

        if not self.tracking or self._half is None or not self.sample_weights:
            return None
        target = new_texture(self.pool, self.size, "R32F")
        framebuffer = gpu.types.GPUFrameBuffer(color_slots=(target,))
        samplers = {
            "accum": self._accum_color,
            "half_accum": self._half,
            "converged": self._masks[self._mask_index],
            "weight": self._weight if self._weight is not None else self._masks[self._mask_index],
        }
        uniforms = {
            "threshold": float(THRESHOLD_SCALE),
            "weight_sum": float(self._weight_sum),
            "per_pixel": 1.0 if self._weight is not None else 0.0,
            "half_scale": self._half_scale(),
        }
        self.fullscreen(self._convergence(True, samplers), framebuffer, samplers, uniforms)
        values = texture_array(target, 1)[..., 0].copy()
        self.give([target])
        return values

    def mask_depth(self, framebuffer):
        """Clear ``framebuffer``'s z-buffer and write the nearest depth where a pixel
        converged, so the lit pass's surfaces fail the depth test there (no shading); with a
        gathering film, only where every pixel within its reach converged too."""
        import gpu

        width, height = self.size
        shader = self.shaders.get(CONVERGED_DEPTH)
        self._batch(shader)
        with framebuffer.bind():
            gpu.state.viewport_set(0, 0, width, height)
            framebuffer.clear(depth=1.0)
            gpu.state.depth_test_set("ALWAYS")
            gpu.state.depth_mask_set(True)
            gpu.state.color_mask_set(False, False, False, False)
            shader.bind()
            shader.uniform_sampler("converged", self.mask)
            shader.uniform_int("reach", int(self.gather_reach))
            self._fullscreen_batch.draw(shader)
            gpu.state.color_mask_set(True, True, True, True)
            gpu.state.depth_mask_set(False)
            gpu.state.depth_test_set("NONE")

    def _ensure_accumulation(self, aux):
        """The float32 accumulation targets of a multi-sample frame (colour, and shadow for a
        final render's Shadow pass), and the targets their resolve writes."""
        import gpu

        width, height = self.size
        if self._accum_color is None or (self._accum_color.width, self._accum_color.height) != (width, height):
            self.give([self._accum_color, self._accum_shadow])
            self._accum_color = new_texture(self.pool, (width, height), "RGBA32F")
            self._accum_shadow = None
            self._accum_fb = gpu.types.GPUFrameBuffer(color_slots=(self._accum_color,))
        if aux and self._accum_shadow is None:
            self._accum_shadow = new_texture(self.pool, (width, height), "R32F")
            self._accum_fb = gpu.types.GPUFrameBuffer(color_slots=(self._accum_color, self._accum_shadow))
        self.centre = None

    def _emission_accumulation(self):
        """The Emission pass's accumulation target (and the framebuffers that add to it and
        resolve it into the pass's target), made on first use at this size."""
        import gpu

        if self._emission_targets is None:
            width, height = self.size
            accum = new_texture(self.pool, (width, height), "RGBA32F")
            self._emission_targets = (
                accum,
                gpu.types.GPUFrameBuffer(color_slots=(accum,)),
                gpu.types.GPUFrameBuffer(color_slots=(self.emission,)),
            )
        return self._emission_targets[0]

    def _scaled_copy(self, framebuffer, sources, scale, aux, blend="NONE", resolve=False, gather=None):
        """framebuffer (<blend>)= scale * sources: colour, and shadow when ``aux`` and the
        accumulation carries it (clamped to [0, 1] when ``resolve``: a mean visibility);
        ``gather``: the sources gathered over the filter's reach (``sampling.gather_uniforms``)."""
        with_shadow = aux and self._accum_shadow is not None
        samplers = {"src_color": sources[0]}
        if with_shadow:
            samplers["src_shadow"] = sources[1]
        program = (SCALED_RESOLVE_SHADOW if resolve else SCALED_COPY_SHADOW) if with_shadow else SCALED_COPY
        self.fullscreen(
            gathered(program, gather, self.gather_reach),
            framebuffer,
            samplers,
            {"scale": scale, **(gather or {})},
            blend,
        )

    def _batch(self, shader):
        from gpu_extras.batch import batch_for_shader

        if self._fullscreen_batch is None:
            self._fullscreen_batch = batch_for_shader(shader, "TRIS", {"pos": ((-1, -1), (3, -1), (-1, 3))})
        return self._fullscreen_batch

    def fullscreen(
        self, program, framebuffer, samplers, uniforms, blend="NONE", depth_test="NONE", blocks=None, defines=None
    ):
        """One full-frame triangle of ``program`` into ``framebuffer`` (at depth 0.5 when
        ``depth_test`` tests it against the framebuffer's z-buffer, which it does not write);
        ``blocks``: {name: uniform buffer} it binds; ``defines``: its variant's."""
        import gpu

        shader = self.shaders.get(program, defines)
        self._batch(shader)
        width, height = self.size
        with framebuffer.bind():
            gpu.state.viewport_set(0, 0, width, height)
            gpu.state.depth_test_set(depth_test)
            if depth_test != "NONE":
                gpu.state.depth_mask_set(False)
            gpu.state.blend_set(blend)
            shader.bind()
            for name, tex in samplers.items():
                shader.uniform_sampler(name, tex)
            for name, block in (blocks or {}).items():
                shader.uniform_block(name, block)
            if any(pc[1] == "origin" for pc in program.push_constants):
                shader.uniform_int("origin", (0, 0))
            integer = {pc[1] for pc in program.push_constants if pc[0].startswith(("INT", "IVEC"))}
            for name, value in uniforms.items():
                (shader.uniform_int if name in integer else shader.uniform_float)(name, value)
            self._fullscreen_batch.draw(shader)
            gpu.state.blend_set("NONE")
            gpu.state.depth_test_set("NONE")

    # --- resources ------------------------------------------------------------------------

    def give(self, textures):
        """Hand textures back to the pool (final renders); without a pool they are freed when
        the last reference goes."""
        if self.pool is not None:
            self.pool.give([t for t in textures if t is not None])

    def _give_targets(self):
        """Every size-bound target back to the pool: a new size, or the end of the render."""
        accum = self._emission_targets[0] if self._emission_targets is not None else None
        self.give(
            [
                self.color,
                self.zbuffer,
                self.shadow,
                self.normal,
                self.emission,
                self._accum_color,
                self._accum_shadow,
                accum,
                self._half,
                *(self._masks or ()),
                self._weight,
                self.shaded,
                self.shaded_total,
            ]
        )
        for part in self._known_parts:
            part.release(self)
        self._emission_fb = None
        self.fb = self.fb_color = self.fb_emit = self._accum_fb = self._resolve_fb = None
        self._half = self._masks = self._mask_fbs = self._weight = None
        self._copy_fbs = {}
        self.tracking, self.converged = False, 0
        self.shaded = self.fb_counted = self.shaded_total = self._shaded_total_fb = None
        self._emission_targets = None
        self.color = self.zbuffer = self.depth = self.shadow = self.normal = self.emission = None
        self._accum_color = self._accum_shadow = None
        self.size = None

    def release(self):
        """Give every target back to the pool: at the end of a final render, inside its GPU
        context."""
        self._give_targets()
        if self.post_ctx is not None:
            self.post_ctx.release()
            self.post_ctx = None
