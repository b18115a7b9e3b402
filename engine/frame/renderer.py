"""One frame as its stages: extract (done by the caller) -> plan -> samples (shadows, lit,
accumulate) -> resolve -> post -> output. The same code serves the viewport and final renders;
only where the camera comes from and where the result goes differ.

The renderer only sequences the frame; each stage keeps its own state: the draw list and its
GPU batches (``draw_list``, ``batches``), the shadow pass (``shadow_pass``), the lit pass
(``lit_pass``) and the film's targets, accumulation and resolve (``film``). A technique the
frame may need (the world's ratio and occlusion, the bounce, settling, depth of field, motion
blur) is a module of ``features/``, called through its hooks: the renderer does not name it.
"""

import dataclasses

import numpy as np

from ..enums import DEBUG_VIEW, DEPTH_FORMAT
from ..post import post_stack
from ..shadows import lightspace
from ..shadows.planning import frame_sizes
from . import debug_view, sampling
from .draw_list import corners_of, draw_list, frame_light_rects, light_masks, lights_in_view
from .features import REGISTRY
from .film import Film, FrameOutput
from .frame_data import AtlasShape, LitInputs, build_frame_data, select_lights
from .lit_pass import LitPass
from .programs import MAX_LIGHTS
from .request import FrameRequest, GpuCaches
from .shadow_pass import UNSET, ShadowPass
from .stats import FrameStats, StageClock
from .world.directions import light_share, needs_directions, portal_cones, world_lights, world_negligible
from .world.probe import PROBE_SHARE, WorldProbe
from .world.sh_light import with_sh_light
from .world.sun import with_sun

__all__ = ["FramePlan", "FrameRequest", "GpuCaches", "Renderer", "Sample"]


@dataclasses.dataclass
class Sample:
    """One sample of a frame, what its stages read and what they leave (``Renderer.sample``,
    ``draw_sample``). Inputs: its ``index`` in the frame, the alpha-hash offset ((s + 1/2) /
    N), the frame's samples (which share the disk filters' taps; 1 for a one-sample frame and
    the pilot), whether it is the frame's ``pilot`` (settling) or the ``settle_test``, its
    world occlusion ((distance, jitter) or None), its lights, its unjittered ``camera`` (maps
    are planned from it), its ``view_camera`` (pixel offset, point of the lens), its ``draws``
    and its ``stats``. Outputs: its lights in view, shadow ``plan`` and ``atlas`` (None
    without maps), ``cameras`` (raster camera, view camera, light rectangles), the view depth
    range the raster camera's depth buffer is fitted to (``depth_range``), frame ``data``,
    the draws the camera sees (``seen``) and the light-linking ``masks``; ``mirrored``: a
    capture's view reflects the scene (``features/planar.py``). The settle test
    draws as the pilot did; the SHADOW_MAPS view shows the last sample's."""

    index: int = 0
    alpha_offset: float = 0.5
    sample_count: int = 1
    pilot: bool = False
    settle_test: bool = False
    ao: tuple | None = None
    lights: list = None
    camera: object = None
    view_camera: object = None
    draws: list = None
    stats: object = None
    origin: np.ndarray = None
    weight: float = 1.0
    offset: tuple = (0.0, 0.0)
    plan: object = None
    atlas: object = None
    cameras: tuple = None
    depth_range: tuple | None = None
    data: object = None
    seen: list = None
    masks: dict = None
    mirrored: bool = False  # its view camera mirrors the scene (a Plane probe's capture): windings turn
    rects: list = None  # the screen rectangle each of its lights in view reaches
    cpu: float = 0.0  # CPU seconds its set-up and map planning took (``Renderer._batch``)


@dataclasses.dataclass
class FramePlan:
    """What ``Renderer.render``'s plan stage decided for one frame (``_plan``, ``_plan_samples``)
    and what every later stage reads: none reads what an earlier call left on the renderer.

    ``request``: the ``FrameRequest``; ``snapshot``: the scene (its world with the SH light of
    an Environment Texture); ``caches``: the renderer's ``GpuCaches``; ``clock`` and
    ``stats``: the frame's ``StageClock`` and ``FrameStats``; ``features``: the techniques this
    frame needs (``features.Feature``, in registry order); ``draws``: the draw list, positions
    relative to ``origin``; ``lights``: those it lights with; ``directions``: directions of
    the world's light per sample with maps, gathered in the light portals' ``cones`` when there
    are any (``world_share``: the world's share of the light in view, None where its light is
    not sampled); ``moving``: indices of the lights that move between samples (``jitter``:
    every light with a map does); ``rects``: each light's screen rectangle for the whole frame
    (``draw_list.frame_light_rects``); ``adaptive``, ``noise`` and ``deadline``: what may end
    the frame early; ``reach``: pixels the samples look beyond the image (pixel filter, lens:
    ``lens_reach``); ``motion``: what moves in the shutter (motion blur); ``reflective``: its
    maps are reflective (the bounce)."""

    request: FrameRequest
    snapshot: object
    caches: GpuCaches
    clock: StageClock
    stats: FrameStats
    origin: np.ndarray
    draws: list
    debug: object  # the DEBUG_VIEW entry
    features: tuple = ()
    lights: list = dataclasses.field(default_factory=list)
    directions: int = 0
    cones: list = dataclasses.field(default_factory=list)
    world_share: float | None = None
    world_negligible: bool = False  # the world's light is under the frame's noise (``world_negligible``)
    first_directions: int = 0  # the first sample that takes directions (after one with AO)
    adaptive: object = None
    noise: bool = False
    deadline: float | None = None
    jitter: bool = False
    moving: set = dataclasses.field(default_factory=set)
    rects: object = None
    reach: float = 0.0
    lens_reach: float = 0.0
    motion: object = None
    reflective: bool = False
    ao_distance: float | None = None
    pass_outputs: dict = dataclasses.field(default_factory=dict)  # the passes' (``features/passes.py``)
    # The lit pass's light rows made so far this frame (``frame_data.kept_light_row``).
    light_rows: dict = dataclasses.field(default_factory=dict)
    # A technique changes every pixel it covers from sample to sample in a way the settle test
    # does not see (the volumes' march): settling keeps no pilot's value.
    unsettled: bool = False
    # Boxes (n, 8, 3 world corners) beyond the draws' that take light: the media's
    # (``features/volumes.py``). The lights that reach them are lit and their maps cover them.
    receivers: object = None

    @property
    def camera(self):
        return self.request.camera

    @property
    def settings(self):
        return self.request.settings

    @property
    def size(self):
        return self.request.size

    @property
    def aux(self):
        return self.request.aux

    @property
    def emission(self):
        return bool(self.request.emission and self.request.aux)

    @property
    def sample_count(self):
        return self.request.sample_count

    @property
    def accumulate(self):
        return self.request.accumulate

    @property
    def world_sampled(self):
        """The frame samples the world's light with maps."""
        return self.directions > 0

    @property
    def world_sh(self):
        """Its surfaces take the world's SH light (not with light portals)."""
        return not self.cones

    def has(self, name):
        """Whether the technique ``name`` (``Feature.name``) works in this frame."""
        return any(f.name == name for f in self.features)


# A frame's samples are drawn in batches of at most this many: their maps planned, then drawn
# together, one instanced draw per caster batch (``Renderer._batch``, ``ShadowPass.batches``).
MAP_BATCH = 8

# While the view moves, a frame's maps keep the sizes of the last navigation frame that
# planned them afresh, this many frames ago at most (``FrameRequest.navigating``).
NAVIGATION_REPLAN = 8


class Renderer:
    """GPU state of one engine instance. Create and use only inside a GPU context."""

    # True: each stage waits for the GPU before and after it (``StageClock``), so FrameStats
    # splits CPU time from GPU time (the benchmarks set it; it stalls the pipeline).
    fence_stages = False

    def __init__(self, pool=None, shaders=None, features=None, store=None):
        """``pool``: a ``gpu_pool.TexturePool`` the frame's targets and shadow atlas come from
        (final renders); ``release`` gives them back. ``shaders``: a ``ShaderCache`` shared
        with other renderers (final renders), else one of its own. ``features``: the
        techniques' classes (``features.REGISTRY`` unless given; one left out is off).
        ``store``: the extension's ``store.Store`` (final renders) its batches are kept in."""
        self.caches = GpuCaches.create(pool, shaders, store)
        self.film = Film(self.caches.shaders, pool)
        self.shadow_pass = ShadowPass(pool)
        self.lit_pass = LitPass(self.caches, self.film)
        self.world_probe = WorldProbe(pool)  # where the world's light gets into an interior
        self.post = post_stack()
        self.features = tuple(cls(self) for cls in (REGISTRY if features is None else features))
        # What the last frame's last sample drew (``Sample``), for inspection: nothing in a
        # frame reads what an earlier call left here.
        self.last_sample = None
        # Kept between calls, keyed by what decides them: (key, moving lights, map sizes) of a
        # frame's first call, for its later calls (the viewport's refinement); (key, map sizes,
        # frames) of the frames drawn while the view moves.
        self._frame_plan = None
        self._navigation = None
        self._seen = None  # (draw list, the draws of it the camera sees)

    pool = property(lambda self: self.caches.pool)
    shaders = property(lambda self: self.caches.shaders)
    textures = property(lambda self: self.caches.textures)
    materials = property(lambda self: self.caches.materials)
    batches = property(lambda self: self.caches.batches)

    @property
    def shadows(self):
        """The shadow atlas (``shadow_maps.ShadowAtlas``)."""
        return self.shadow_pass.atlas

    def render(self, snapshot, request, on_sample=None):
        """Samples ``request.samples[0] .. [1] - 1`` of the frame ``request`` asks for (a
        ``FrameRequest``; ``frame/sampling.py``), added to the samples this renderer already
        accumulated for it (a start of 0 begins the frame afresh), then the post stack on
        their filtered average. One sample of one is exactly the single-sample frame, with no
        accumulation. Depth and normal are the centred sample's, shadow and emission averaged
        like colour. ``on_sample(done)`` after each sample; returning False stops the frame
        there (cancel). Adaptive sampling's Noise Threshold stops converged pixels (checked
        every few samples on the GPU; they are not shaded again) and ends the frame when every
        pixel has converged; its time limit ends it after the first sample that reaches it,
        counted from this call's first sample unless ``request.deadline`` says when. Neither
        looks at a clock when there is no time limit: a frame stays a function of the scene and
        its settings. A navigating frame's maps keep the sizes a navigation frame planned at
        most NAVIGATION_REPLAN frames before (one fit per map, not two), and the frame after
        the view stops plans afresh.

        The frame's stages, in order: plan (``_plan``: what the frame draws, its lights and
        the world's, the techniques it needs and what they add, which lights move and their
        maps' sizes), then per sample the techniques' stages before it (settling's test), the
        sample (``_sample_at``: shadow maps, lit pass, accumulate), then resolve
        (``_resolve``) and post (``_post``). Each takes the ``FramePlan`` (and the ``Sample``)."""
        clock = StageClock(self.wait_gpu if self.fence_stages else None)
        counters = (
            self._uploaded(),
            self.shaders.compiled,
            self.shaders.compile_seconds,
            self.batches.uploaded,
            self.textures.upload_bytes,
        )
        self.film.clock = clock
        with clock.stage("prepare"):
            frame = self._plan(snapshot, request, clock)
            self._plan_samples(frame)
        stats = frame.stats
        drawn = None
        pixels = request.width * request.height
        s, end = request.samples
        while s < end and not (stats.stopped or stats.cancelled):
            for feature in frame.features:
                feature.before_sample(frame, s)
            if frame.accumulate and self.film.converged >= pixels:
                stats.stopped = "converged"  # every pixel settled, or a later call of a converged frame
                break
            batch = self._batch(frame, s, self._batch_end(frame, s, end))
            s += len(batch)
            for group in self.shadow_pass.batches(frame, batch):
                start = clock.cpu_seconds
                with clock.stage("shadow pass"):
                    self.shadow_pass.draw_batch(frame, group)
                shared = clock.cpu_seconds - start  # booked to the group's first sample
                for sample in group:
                    drawn = self._sample_at(frame, sample, shared)
                    shared = 0.0
                    if frame.deadline is not None and frame.accumulate and not stats.stopped:
                        self.film.finish()  # the sample's GPU work done, so the clock counts it
                        if sampling.clock() >= frame.deadline:
                            stats.stopped = "time limit"
                    if on_sample is not None and on_sample(sample.index + 1) is False:
                        stats.cancelled = True
                    if stats.stopped or stats.cancelled:
                        break
                if stats.stopped or stats.cancelled:
                    break
        self.last_sample = drawn
        with clock.stage("resolve"):
            self._resolve(frame, drawn)
        with clock.stage("post"):
            color, debug_image = self._post(frame, drawn)
        stats.messages.extend(m for m in self.textures.messages() if m not in stats.messages)
        stats.cpu_seconds, stats.gpu_seconds = clock.cpu, clock.gpu
        self.film.clock = None  # a fenced clock holds the renderer (``close``)
        self._seen = None  # the frame's draws, not kept past it
        self.lit_pass.end_frame()
        stats.upload_bytes = self._uploaded() - counters[0]
        stats.mesh_upload_bytes = self.batches.uploaded - counters[3]
        stats.image_upload_bytes = self.textures.upload_bytes - counters[4]
        stats.shaders_compiled = self.shaders.compiled - counters[1]
        stats.compile_seconds = self.shaders.compile_seconds - counters[2]
        return self._output(frame, color, debug_image)

    def _plan(self, snapshot, request, clock):
        """The plan stage: what the frame draws (the draw list, relative to the frame origin),
        the world's light (its SH light, the world's sun, light portals or an interior's
        openings; none of them where its light is under the frame's Noise Threshold), the
        techniques the frame needs and what each adds to the plan, the lights it lights with
        and the film it draws into. Returns the ``FramePlan`` the later stages read."""
        stats = FrameStats()
        settings, camera = request.settings, request.camera
        self.film.ensure(request.width, request.height, request.aux, request.emission and request.aux)
        # The frame origin: the GPU gets every position relative to the camera (model matrices,
        # lights, the camera's and each map's view), computed here in float64, so a scene far
        # from the world origin keeps float32's precision where it is seen. Maps do not depend
        # on it (each is drawn and read through the same shift) and stay reusable when it moves.
        origin = camera.position if np.all(np.isfinite(camera.position)) else np.zeros(3)
        draws = draw_list(snapshot, self.batches, stats, origin, camera, settings, request.size)
        stats.messages.extend(getattr(snapshot, "messages", ()))
        self.textures.forget(getattr(snapshot, "images_changed", ()))
        snapshot = self._world(snapshot)
        debug = DEBUG_VIEW[getattr(settings, "debug_view", "NONE")]
        frame = FramePlan(request, snapshot, self.caches, clock, stats, origin, draws, debug)
        # A lit debug view's values are not colour: no noise estimate of theirs ends a frame.
        frame.adaptive = request.adaptive if frame.accumulate and not debug.lit else None
        frame.noise = frame.adaptive is not None and frame.adaptive.threshold > 0.0
        # A multi-sample frame's pixel offsets reach Filter Size pixels beyond the image (and
        # depth of field's points of the lens further): its maps and bins are planned for them.
        frame.reach = max(float(settings.filter_size), 0.0) if frame.accumulate else 0.0
        threshold = frame.adaptive.threshold if frame.adaptive is not None else 0.0
        frame.world_negligible = world_negligible(
            snapshot.world if snapshot.world is not None else snapshot.world_color, threshold
        )
        if not frame.world_negligible:
            self._world_directions(frame)
        # The techniques, in registry order: each decides over what is planned so far.
        features = []
        for feature in self.features:
            if feature.wanted(frame):
                feature.plan(frame)
                features.append(feature)
        frame.features = tuple(features)
        stats.techniques = [f.name for f in features]
        self.shadow_pass.begin_frame(frame.reach, frame.reflective, frame.receivers, request.navigating)
        room = MAX_LIGHTS - frame.directions
        frame.lights = select_lights(snapshot.lights, camera.position, room)
        if len(frame.lights) < len(snapshot.lights):
            stats.messages.append(
                f"Penumbra: {len(snapshot.lights)} lights; only the {room} that contribute most to the view are lit"
            )
        return frame

    def _world(self, snapshot):
        """The snapshot with its world's SH light (an Environment Texture's, projected on the
        GPU) and World > Settings > Sun as a light where it is above the threshold."""
        world = with_sh_light(snapshot.world, self.textures, self.shaders)
        if world is not snapshot.world:
            snapshot = dataclasses.replace(snapshot, world=world, world_color=world.mean)
        world, sun = with_sun(snapshot.world)
        if sun is not None:
            snapshot = dataclasses.replace(
                snapshot, world=world, world_color=world.mean, lights=[*snapshot.lights, sun]
            )
        return snapshot

    def _world_directions(self, frame):
        """Where the world's light is sampled with maps (``world/directions.py``): the world's
        share of the light reaching what the camera sees (``frame.world_share``) and the cones
        that gather its directions: its light portals', or without portals the guide of an
        interior's openings (``world/probe.py``). Through cones the directions carry all of the
        world's light, in every sample (``settings.world_samples`` each); without them a
        technique may sample it (``features/world_ratio.py``)."""
        snapshot, settings = frame.snapshot, frame.settings
        if not needs_directions(snapshot.world, settings):
            return
        # Light portals: the directions gather where the world's light enters what the camera
        # sees, and carry all of its light (no SH light on the surfaces of those samples). A
        # one-sample frame then takes its directions too: the SH light of a room's sky, even
        # occluded on screen, is nothing like the light through its windows.
        seen = [d for d in frame.draws if d.instance.camera]
        if not seen:
            frame.world_share = 1.0
            return
        box = corners_of(seen).reshape(-1, 3)
        frame.world_share = light_share(snapshot.world, snapshot.lights, 0.5 * (box.min(axis=0) + box.max(axis=0)))
        if getattr(snapshot, "portals", ()):
            frame.cones = portal_cones(snapshot.portals, box.min(axis=0), box.max(axis=0))
        elif frame.world_share >= PROBE_SHARE:
            # No light portal, and the world lights the frame: an interior's openings, found by
            # the world's probe, stand in for them.
            camera = frame.camera
            frame.cones = self.world_probe.cones(
                frame.draws, snapshot.world, camera.position, frame.origin, self.caches, frame.stats
            )
            frame.stats.world_guided = bool(frame.cones)
        if frame.cones:
            frame.directions = int(settings.world_samples)

    def _plan_samples(self, frame):
        """The rest of the plan stage: the film's targets (the techniques' among them), which
        lights move between the frame's samples and the sizes of their maps (the frame's first
        plan; a later call of the same frame keeps the first call's), the screen rectangles
        each light can reach and when the frame's time runs out."""
        film, settings, lights, request = self.film, frame.settings, frame.lights, frame.request
        width, height = frame.size
        stats = frame.stats
        if not frame.accumulate:
            film.converged = 0  # a single sample shades every pixel, whatever an earlier frame left
            film.parts = ()  # nor keeps a technique's targets of its own
            # While the view moves, maps keep the sizes planned NAVIGATION_REPLAN frames ago.
            nav_key = (width, height, tuple(lt.use_shadow for lt in lights))
            last = self._navigation
            if request.navigating and last is not None and last[0] == nav_key and last[2] % NAVIGATION_REPLAN:
                self.shadow_pass.use_sizes(last[1])
                self._navigation = (nav_key, last[1], last[2] + 1)
            else:
                if request.navigating and last is not None and last[0] == nav_key and last[1] is not None:
                    self.shadow_pass.hint_sizes(last[1])  # sizes kept where density asks for close ones
                self._navigation = (nav_key, None, 1) if request.navigating else None
        else:
            targets = {}
            for feature in frame.features:
                targets.update(feature.film(frame))
            parts = tuple(p for p in (feature.film_part(frame) for feature in frame.features) if p is not None)
            # The NOISE view shows the estimate even where no threshold uses it.
            film.begin(
                frame.aux,
                frame.emission,
                fresh=request.samples[0] == 0,
                adaptive=frame.noise or frame.debug.id == "NOISE",
                gather_reach=sampling.gather_reach(settings.filter_size)
                if sampling.gathers(settings.filter_size)
                else 0,
                parts=parts,
                **targets,
            )
            self._moving_lights(frame)
        stats.lights_sampled = len(frame.moving)
        # Which part of the screen each light can reach: once a frame, padded by how far its
        # samples move it and by the camera's pixel offsets (light bins, lights out of view).
        if frame.motion is None:  # with motion blur each sample's own (``lights_in_view``)
            frame.rects = frame_light_rects(
                lights, frame.draws, frame.camera, width, height, frame.reach, frame.receivers
            )
        deadline = request.deadline
        if frame.adaptive is not None and frame.adaptive.time_limit > 0.0 and deadline is None:
            deadline = sampling.clock() + frame.adaptive.time_limit
        frame.deadline = deadline

    def _moving_lights(self, frame):
        """Which lights of a frame of several samples move between them, and their maps' sizes."""
        lights, settings = frame.lights, frame.settings
        # With map jitter every shadowed light changes from sample to sample (its maps'
        # texel grid), so lights with an extent are sampled on it however small their penumbra.
        frame.jitter = bool(settings.shadow_map_jitter)
        # The frame's centred plan decides which lights move and the sizes of their maps; a
        # later call of the same frame (the viewport's next refinement: nothing changed, or the
        # frame would start afresh) keeps what the first call decided (a cache keyed by what
        # decides it). With motion blur every sample plans its maps from its own scene
        # (``features/motion_blur.py``): the frame's centred plan says only which lights move.
        frame_key = (frame.sample_count, frame.jitter, tuple(lt.use_shadow for lt in lights))
        cached = self._frame_plan is not None and self._frame_plan[0] == frame_key
        if frame.request.samples[0] > 0 and cached and frame.motion is None:
            frame.moving, sizes = self._frame_plan[1:]
            self.shadow_pass.use_sizes(sizes)
            return
        first = self.shadow_pass.first_plan(frame.draws, lights, frame.camera, settings, self.film.size, True)
        frame.moving = sampling.sampled_lights(lights, first, every=frame.jitter)
        if frame.jitter:
            frame.moving |= {i for i in first.lights if i < len(lights)}
        if frame.motion is None:
            self.shadow_pass.keep_sizes(first, settings, lights)
            self._frame_plan = (frame_key, frame.moving, self.shadow_pass.sizes)

    def sample(self, frame, s, pilot=False, lights=None):
        """Sample ``s`` of ``frame`` as its stages take it (``Sample``): its pixel offset, its
        lights (moving ones at their point for ``s``, the world's directions), and what the
        frame's techniques change of it (``Feature.prepare``). ``pilot``: the frame's pilot
        sample (settling) instead, with ``lights`` (every moving light at its centre), through
        the pixel's and the lens's centres, without the world's directions."""
        accumulate, count = frame.accumulate, frame.sample_count
        sample = Sample(
            index=s,
            alpha_offset=(s + 0.5) / count if accumulate and not pilot else 0.5,
            sample_count=count if accumulate and not pilot else 1,
            pilot=pilot,
            lights=frame.lights if lights is None else lights,
            camera=frame.camera,
            view_camera=frame.camera,
            draws=frame.draws,
            stats=frame.stats,
            origin=frame.origin,
        )
        for feature in frame.features:
            feature.prepare(frame, sample)
        if pilot:
            return sample
        stats = frame.stats
        if accumulate:
            dx, dy, sample.weight = sampling.pixel_offset(s, frame.settings.filter_size)
            sample.offset = (dx, dy)
            if dx or dy:
                jittered = sampling.jittered_projection(sample.view_camera.projection, dx, dy, *frame.size)
                sample.view_camera = dataclasses.replace(sample.view_camera, projection=jittered)
        sample.lights = [
            sampling.light_at_sample(lt, i, s, count, frame.jitter, progressive=frame.noise)
            if i in frame.moving
            else lt
            for i, lt in enumerate(sample.lights)
        ]
        if frame.directions and s >= frame.first_directions:
            index = (s - frame.first_directions) * frame.directions
            sample.lights += world_lights(frame.snapshot.world, index, frame.directions, cones=frame.cones)
            stats.world_directions += frame.directions
        return sample

    def _batch_end(self, frame, s, end):
        """Where the batch of samples that starts at ``s`` ends (the frame's samples run to
        ``end``): at most MAP_BATCH samples of a frame that accumulates, sharing one draw list
        (not with motion blur, where each sample has its own), and never past a sample after
        which adaptive sampling checks the noise or before which a technique works
        (``Feature.starts_batch``: settling's test), so a batch ends where the frame may. The
        first sample is a batch of its own: settling's test reads it, and a frame with settling
        and one without then draw their later samples in the same batches, their maps placed
        alike, so they agree to the bit where no pixel settled (a map placed elsewhere in the
        atlas may rasterise a texel's edge otherwise: ``gl_Position``'s rounding)."""
        if not frame.accumulate or frame.motion is not None or s == 0:
            return s + 1
        last = min(end, s + MAP_BATCH)
        for k in range(s + 1, last):
            if frame.noise and frame.adaptive.checks_at(k):
                return k
            if any(feature.starts_batch(frame, k) for feature in frame.features):
                return k
        return last

    def _batch(self, frame, s, end):
        """Samples ``s`` .. ``end - 1`` set up (``sample``: the techniques' ``before_sample``
        first for all but ``s``, whose the caller ran), with their lights in view and their
        maps planned (``ShadowPass.plan_sample``), nothing drawn: the batch whose maps are drawn
        together (``ShadowPass.batches``, ``draw_batch``). A batch of one is the frame one
        sample at a time."""
        clock = frame.clock
        batch = []
        for k in range(s, end):
            if k > s:
                for feature in frame.features:
                    feature.before_sample(frame, k)
            start = clock.cpu_seconds
            with clock.stage("sample set-up"):
                sample = self.sample(frame, k)
                self._lights_in_view(frame, sample)
            with clock.stage("shadow pass"):
                sample.plan = self.shadow_pass.plan_sample(frame, sample)
            sample.cpu = clock.cpu_seconds - start
            batch.append(sample)
        return batch

    def _sample_at(self, frame, sample, shared=0.0):
        """``sample`` (set up, its maps drawn: ``_batch``) drawn (``draw_lit``), then its weight
        added to the film and, every few samples, the noise check (``stats.stopped``).
        ``shared``: CPU seconds of its batch's map pass booked to it."""
        film, settings, stats, clock = self.film, frame.settings, frame.stats, frame.clock
        accumulate, count = frame.accumulate, frame.sample_count
        s = sample.index
        sample_start = clock.cpu_seconds - sample.cpu - shared
        self.draw_lit(frame, sample)
        with clock.stage("accumulate"):
            if accumulate:
                stats.pixel_samples_skipped += film.converged
                gather = sampling.gather_uniforms(*sample.offset, settings.filter_size)  # the gathering film
                film.accumulate(sample.weight, frame.aux, frame.emission, s, gather)
            if frame.aux and accumulate and s == 0:  # the centred sample's depth and normal
                film.keep_centre()
            stats.samples += 1
            # (No check after a frame's last sample: it ends there anyway.)
            adaptive = frame.adaptive
            last = s + 1 == count
            if frame.noise and not last and adaptive.checks_at(s + 1):
                if film.check(adaptive.threshold) >= frame.size[0] * frame.size[1]:
                    stats.stopped = "converged"
        stats.sample_cpu_seconds.append(clock.cpu_seconds - sample_start)
        return sample

    def draw_sample(self, frame, sample):
        """Draw ``sample`` (a ``Sample``) of ``frame`` on its own (a batch of one): its shadow
        maps (planned from its unjittered camera, so a light that does not move between
        samples keeps its map), then ``draw_lit``. Fills in and returns ``sample``."""
        self._lights_in_view(frame, sample)
        with frame.clock.stage("shadow pass"):
            self.shadow_pass.draw(frame, sample)
        return self.draw_lit(frame, sample)

    def _lights_in_view(self, frame, sample):
        """The sample's lights that light something it sees (``sample.lights``) and the screen
        rectangles they reach (``sample.rects``)."""
        width, height = self.film.size
        sample.lights, sample.rects = lights_in_view(
            sample.lights, sample.draws, sample.view_camera, width, height, sample.stats, frame.rects, frame.receivers
        )

    def draw_lit(self, frame, sample):
        """``sample`` after its maps are drawn (``sample.plan``): the techniques' work before
        the lit pass (``Feature.before_lit``: the world occlusion's depth prepass through the
        raster camera), then the lit pass seen through its view camera, then the techniques'
        work after it. Fills in and returns ``sample``."""
        clock = frame.clock
        view_camera, camera, rects = sample.view_camera, sample.camera, sample.rects
        sample.atlas = self.shadows if sample.plan is not None and sample.plan.tiles else None
        depth_range = self.shadow_pass.depth_range
        if depth_range is UNSET:  # no shadow plan this frame: the quick, wider bound
            draws = sample.draws
            depth_range = lightspace.box_depth_range(camera.projection, camera.view, corners_of(draws), camera.is_ortho)
        # The lit pass rasterises with the depth buffer spread over what the camera sees.
        sample.depth_range = depth_range
        fitted = lightspace.depth_fitted(view_camera.projection, view_camera.is_ortho, depth_range)
        raster_camera = (
            view_camera if fitted is view_camera.projection else dataclasses.replace(view_camera, projection=fitted)
        )
        sample.cameras = (raster_camera, view_camera, rects)
        for feature in frame.features:
            feature.before_lit(frame, sample)
        with clock.stage("lit pass"):
            self.lit(frame, sample)
        for feature in frame.features:
            feature.after_lit(frame, sample)
        sample.stats.binned = sample.data.bins is not None
        return sample

    def lit(self, frame, sample, target=None):
        """The lit pass of ``sample`` (its lights, the maps of its plan, its cameras and light
        rectangles), with the frame's techniques' parts (``Feature.lit``); ``target``: the
        settle test's framebuffer (``sample.settle_test``, ``features/settling.py``). Fills in
        ``sample.data`` (the frame data it drew with)."""
        parts = tuple(feature.lit(frame, sample) for feature in frame.features)
        self._frame_data(frame, sample, parts, frame.aux and target is None, sample.cameras[2])
        if target is not None:
            self.lit_pass.draw_settle_test(sample, target)
        else:
            self.lit_pass.draw(frame, sample)
        return sample.data

    def capture(self, frame, sample, lit_pass, parts):
        """A lit pass of ``sample`` seen from elsewhere (``sample.cameras``: a Plane probe's
        mirrored camera) into ``lit_pass``'s film, with ``parts`` for the techniques' (what a
        capture takes: ``Feature.capture``): colour, normal and view depth, the world's image
        behind it whatever the film's transparency, no light bins (the camera's rectangles),
        no debug view. Where the surfaces take the world's SH light, its directions light
        nothing there unless a part takes their ratio (``WORLD_RATIO``)."""
        settings = dataclasses.replace(frame.settings, film_transparent=False, debug_view="NONE")
        request = dataclasses.replace(frame.request, aux=True, emission=False, settings=settings)
        seen_from = dataclasses.replace(frame, request=request)
        world_sh = frame.world_sh or not any(lt.world for lt in sample.lights)
        ratio = any(dict(p.program.defines).get("WORLD_RATIO") for p in parts if p.program is not None)
        if world_sh and not ratio and any(lt.world for lt in sample.lights):
            sample.lights = [dataclasses.replace(lt, color=np.zeros(3)) if lt.world else lt for lt in sample.lights]
        self._frame_data(seen_from, sample, parts, True, None)
        lit_pass.draw(seen_from, sample)
        return sample.data

    def _frame_data(self, frame, sample, parts, aux_outputs, rects):
        """``sample.data`` (the frame data its lit pass binds, with the techniques' ``parts``),
        the draws its camera sees and the light-linking masks."""
        snapshot = frame.snapshot
        lights, plan, atlas = sample.lights, sample.plan, sample.atlas
        inputs = LitInputs(
            atlas=AtlasShape(atlas.size, atlas.columns, atlas.depth_format) if atlas else AtlasShape(),
            aux_outputs=aux_outputs,
            rects=rects,
            size=self.film.size,
            alpha_offset=sample.alpha_offset,
            origin=frame.origin,
            sample_count=sample.sample_count,
            sample_index=sample.index,
            world_sampled=frame.world_sampled,
            world_sh=frame.world_sh or not any(lt.world for lt in lights),
            parts=parts,
            light_rows=frame.light_rows,
        )
        world = snapshot.world if snapshot.world is not None else snapshot.world_color
        sample.data = build_frame_data(lights, sample.cameras[0], world, frame.settings, plan, inputs)
        seen = self._seen
        if seen is None or seen[0] is not sample.draws:  # the same list for a frame's samples
            seen = self._seen = (sample.draws, [d for d in sample.draws if d.instance.camera])
        sample.seen = seen[1]
        sample.masks = (
            light_masks(sample.seen, lights, sample.data.order) if sample.data.variant.light_linking else None
        )

    def _resolve(self, frame, drawn):
        """The resolve stage: the film's accumulation divided by its weights, the techniques'
        resolves; the batches the frame did not use let go; a navigation frame that planned
        afresh keeps its map sizes."""
        film, stats = self.film, frame.stats
        stats.pixels_converged = film.converged if frame.accumulate else 0
        if frame.accumulate and stats.samples:
            film.resolve(frame.aux, frame.emission)
        for feature in frame.features:
            feature.resolve(frame)
        self.batches.keep({(key, geo.serial) for key, geo in frame.snapshot.geometry.items()})
        nav = self._navigation
        plan = drawn.plan if drawn is not None else None
        if nav is not None and nav[1] is None and plan is not None:  # a navigation frame that planned afresh
            sizes = frame_sizes(plan, max(1, int(frame.settings.shadow_map_size)))
            self._navigation = (nav[0], sizes, nav[2])

    def _post(self, frame, drawn):
        """The post stage: the post stack on the resolved image, or a debug view instead of
        both; the frame's memory in its stats. Returns (colour texture, debug image or None)."""
        film, settings, stats = self.film, frame.settings, frame.stats
        debug_image = None
        if frame.debug.id != "NONE":  # the view instead of the image (and instead of the post stack)
            occluded = stats.ao_prepasses > 0
            debug_image = self._debug_view(frame.debug.id, frame.accumulate, settings, drawn, occluded)
            color = debug_view.upload(debug_image, settings.pixel_scale)
            stats.debug_legend = debug_image.legend
        else:
            color = self._post_pass(settings, stats)
        plan = drawn.plan if drawn is not None else None
        stats.shadow_bytes = self.shadows.memory_bytes if plan is not None and plan.tiles else 0
        stats.texture_bytes = (
            film.target_bytes(frame.aux, frame.accumulate)
            + stats.shadow_bytes
            + film.post_ctx.memory_bytes
            + self.textures.bytes
            + sum(feature.memory_bytes(frame) for feature in frame.features)
        )
        return color, debug_image

    def _output(self, frame, color, debug_image):
        """The frame's ``FrameOutput``: its image and, with ``aux``, its passes."""
        film, stats = self.film, frame.stats
        width, height = frame.size
        if not frame.aux:
            out = FrameOutput(color, None, None, stats, width, height, lit=film.color)
            out.debug = debug_image
            out.passes = dict(frame.pass_outputs)
            return out
        out = FrameOutput(color, film.depth, film.shadow, stats, width, height, lit=film.color, normal=film.normal)
        out.debug = debug_image
        out.emission = film.emission if frame.emission else None
        out.passes = dict(frame.pass_outputs)
        if frame.accumulate and film.centre is not None:
            out.depth_data, out.normal_data = film.centre
        return out

    def _debug_view(self, view, accumulate, settings, last, occluded=False):
        """The debug view ``view`` of the frame just rendered (``debug_view.DebugImage``);
        ``last``: its last sample (``Sample``: the SHADOW_MAPS view's plan and lights);
        ``occluded``: its samples ran the world's ambient occlusion (WORLD_AO)."""
        from .film import texture_array

        film = self.film
        width, height = film.size
        if DEBUG_VIEW[view].lit:
            return debug_view.lit_view(view, texture_array(film.color, 4), occluded)
        if view == "SAMPLES":
            samples = film.samples_array() if accumulate else np.ones((height, width), np.float32)
            return debug_view.samples_view(samples)
        if view == "NOISE":
            return debug_view.noise_view(film.error_array() if accumulate else None, film.size)
        atlas = self.shadows
        plan = last.plan if last is not None else None
        depths = None
        if plan is not None and plan.tiles and atlas.texture is not None:
            channels = DEPTH_FORMAT[atlas.depth_format].channels
            depths = debug_view.atlas_depths(texture_array(atlas.texture, channels), atlas.depth_format)
        return debug_view.shadow_maps_view(depths, plan, last.lights if last is not None else [], film.size)

    def _post_pass(self, settings, stats):
        ctx = self.film.post_ctx
        ctx.frame = settings.frame
        ctx.pixel_scale = settings.pixel_scale
        ctx.stats = stats
        return self.post.run(ctx, self.film.color, settings.layers)

    def _uploaded(self):
        """Bytes this renderer's stages have sent to the GPU since it was made."""
        return self.lit_pass.uploaded + self.shadows.uploaded + self.caches.uploaded

    def wait_gpu(self):
        """Return once the GPU has finished what was asked of it (a one-pixel read-back of the
        frame's colour target and of the shadow atlas): the fence of ``fence_stages``."""
        film = self.film
        fb = film.fb or film.fb_color
        if fb is not None:
            with fb.bind():
                fb.read_color(0, 0, 1, 1, 4, 0, "FLOAT")
        atlas = self.shadows
        if atlas._framebuffer is not None:
            with atlas._framebuffer.bind():
                if atlas.depth_format == "FLOAT32":
                    atlas._framebuffer.read_depth(0, 0, 1, 1)
                else:
                    atlas._framebuffer.read_color(0, 0, 1, 1, 4, 0, "FLOAT")

    def release(self):
        """Give the frame's targets and the shadow atlas back to the pool (final renders) and
        free every other GPU object the renderer holds, now: inside its GPU context, where the
        engine lets it go (``close``). The renderer is not used again."""
        if self.pool is not None:
            self.film.release()
            self.shadows.free()
            for feature in self.features:
                feature.release()
            self.world_probe.release()
        self.close()

    def close(self):
        """Drop what could lead back to the renderer (the film's clock, whose fence is the
        renderer's; its techniques hold it weakly), so that letting it go frees its
        framebuffers, blocks, batches and textures at once, in the GPU context that is current,
        not whenever Python's cycle collector runs: possibly in another render's context, or in
        none (``test_sample_batches.py``: ``test_a_renderer_let_go_frees_its_gpu_objects_at_once``)."""
        self.features = ()
        self.film.clock = None
