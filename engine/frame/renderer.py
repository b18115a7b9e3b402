"""One frame as its stages: extract (done by the caller) -> shadows -> lit -> post -> output.
The same code serves the viewport and final renders; only where the camera comes from and
where the result goes differ.

The renderer only sequences the frame; each stage keeps its own state: the draw list and its
GPU batches (``draw_list``, ``batches``), the shadow pass (``shadow_pass``), the lit pass
(``lit_pass``) and the film's targets, accumulation and resolve (``film``).
"""

import dataclasses

import numpy as np

from ..enums import DEBUG_VIEW, DEPTH_FORMAT
from ..post import post_stack
from ..scene.textures import TextureCache
from ..shadows import lightspace
from ..shadows.planning import frame_sizes
from . import debug_view, sampling
from . import motion as motion_mod
from .batches import Batches
from .draw_list import corners_of, draw_list, frame_light_rects, light_masks, lights_in_view
from .film import Film, FrameOutput
from .frame_data import build_frame_data, select_lights
from .lens import lens_camera, lens_offset, lens_reach
from .lit_pass import LitPass
from .material_blocks import MaterialBlocks
from .programs import MAX_LIGHTS
from .settle import flag_reach
from .settle import settle as settle_pixels
from .shadow_pass import UNSET, ShadowPass
from .stats import FrameStats, StageClock
from .world.directions import (
    directions_per_sample,
    light_share,
    needs_directions,
    portal_cones,
    world_lights,
    world_negligible,
)
from .world.occlusion import WorldAO
from .world.probe import PROBE_SHARE, WorldProbe
from .world.sh_light import with_sh_light
from .world.sun import with_sun


@dataclasses.dataclass(frozen=True)
class SampleSpec:
    """What varies from sample to sample of a frame, for ``Renderer._sample`` and ``_lit``:
    the alpha-hash offset ((s + 1/2) / N), the frame's samples (which share the disk filters'
    taps), whether it is the frame's pilot, the world's ambient occlusion ((distance, jitter)
    or None) and its index in the frame."""

    alpha_offset: float = 0.5
    sample_count: int = 1
    pilot: bool = False
    ao: tuple = None
    index: int = 0


@dataclasses.dataclass
class SampleResult:
    """What one sample drew: its lights in view (what its plan indexes), its shadow plan, its
    lit pass's (raster camera, view camera, light rectangles) and frame data. The settle test
    draws as the pilot's did; the SHADOW_MAPS view shows the last sample's."""

    lights: list
    plan: object
    cameras: tuple
    data: object = None
    draws: list = None  # its draw list (a motion-blurred sample's own; None: the frame's)


@dataclasses.dataclass
class FramePlan:
    """What ``Renderer.render``'s plan stage decided for one frame (``_plan``, ``_plan_samples``):
    the later stages read this and their own arguments, nothing an earlier call left behind.

    ``snapshot``: the scene (its world with the SH light of an Environment Texture);
    ``draws``: the draw list, positions relative to ``origin``; ``lights``: those it lights
    with; ``directions``: directions of the world's light per sample with maps, gathered in
    the light portals' ``cones`` when there are any; ``moving``: indices of the lights that
    move between samples (``jitter``: every light with a map does); ``rects``: each light's
    screen rectangle for the whole frame (``draw_list.frame_light_rects``); ``adaptive``,
    ``noise``, ``settle`` and ``deadline``: what may end the frame early."""

    snapshot: object
    camera: object
    settings: object
    size: tuple
    origin: np.ndarray
    draws: list
    lights: list
    aux: bool
    emission: bool
    sample_count: int
    debug: object  # the DEBUG_VIEW entry
    directions: int = 0
    cones: list = dataclasses.field(default_factory=list)
    world_negligible: bool = False  # the world's light is under the frame's noise (``world_negligible``)
    first_directions: int = 0  # the first sample that takes directions (after one with AO)
    adaptive: object = None
    noise: bool = False
    settle: bool = False
    deadline: float | None = None
    jitter: bool = False
    moving: set = dataclasses.field(default_factory=set)
    rects: object = None
    reach: float = 0.0  # pixels the samples look beyond the image (pixel filter, lens)
    motion: object = None  # ``motion.Motion``: each sample at its own time in the shutter
    lens_reach: float = 0.0  # of which the lens's: its widest circle of confusion's radius
    _ao_distance: float | None = None

    @property
    def accumulate(self):
        return self.sample_count > 1

    @property
    def world_sampled(self):
        """The frame samples the world's light with maps."""
        return self.directions > 0

    @property
    def world_sh(self):
        """Its surfaces take the world's SH light (not with light portals)."""
        return not self.cones

    @property
    def world_ratio(self):
        """Without portals the directions shadow the SH light as a ratio of their sums over
        the frame's samples (never negative; lit_world.glsl WORLD_RATIO); with portals they
        carry the whole light, f cos V L / p, never negative either."""
        return self.directions > 0 and not self.cones

    def world_ao(self, s):
        """Sample ``s``'s ambient occlusion of the world (``sampling.world_ao_sample``):
        (distance, jitter), or None: not this sample, or none where light portals send the
        world's directions into every sample."""
        snapshot = self.snapshot
        world = snapshot.world if snapshot.world is not None else snapshot.world_color
        if self.cones or not sampling.world_ao_sample(s, self.accumulate, self.settings, world, self.debug.id):
            return None
        if self.world_negligible and self.debug.id != "WORLD_AO":  # occluding it could change no pixel
            return None
        if self._ao_distance is None:
            self._ao_distance = sampling.world_ao_distance(self.settings, corners_of(self.draws)) if self.draws else 0.0
        return (self._ao_distance, sampling.ao_jitter(s)) if self._ao_distance > 0.0 else None


# While the view moves, a frame's maps keep the sizes of the last navigation frame that
# planned them afresh, this many frames ago at most (``Renderer.render``'s ``navigating``).
NAVIGATION_REPLAN = 8


class Renderer:
    """GPU state of one engine instance. Create and use only inside a GPU context."""

    # True: each stage waits for the GPU before and after it (``StageClock``), so FrameStats
    # splits CPU time from GPU time (the benchmarks set it; it stalls the pipeline).
    fence_stages = False

    def __init__(self, pool=None, shaders=None):
        """``pool``: a ``gpu_pool.TexturePool`` the frame's targets and shadow atlas come from
        (final renders); ``release`` gives them back. ``shaders``: a ``ShaderCache`` shared
        with other renderers (final renders), else one of its own."""
        from ...shaders.loader import ShaderCache

        self.pool = pool
        self.shaders = shaders if shaders is not None else ShaderCache()
        self.textures = TextureCache()
        self.materials = MaterialBlocks()
        self.batches = Batches()
        self.film = Film(self.shaders, pool)
        self.shadow_pass = ShadowPass(pool)
        self.lit_pass = LitPass(self.shaders, self.materials, self.textures)
        self.world_ao = WorldAO(pool)  # the camera depth prepass of the world's ambient occlusion
        self.world_probe = WorldProbe(pool)  # where the world's light gets into an interior
        self.post = post_stack()
        # What the last frame's last sample drew (``SampleResult``), for inspection: nothing
        # in a frame reads what an earlier call left here.
        self.last_sample = None
        self._clock = StageClock()  # the current frame's (``render``)
        # Kept between calls, keyed by what decides them: (key, moving lights, map sizes) of a
        # frame's first call, for its later calls (the viewport's refinement); (key, map sizes,
        # frames) of the frames drawn while the view moves.
        self._frame_plan = None
        self._navigation = None

    @property
    def shadows(self):
        """The shadow atlas (``shadow_maps.ShadowAtlas``)."""
        return self.shadow_pass.atlas

    def render(
        self,
        snapshot,
        camera,
        settings,
        width,
        height,
        aux=True,
        samples=(0, 1),
        sample_count=1,
        on_sample=None,
        emission=False,
        adaptive=None,
        deadline=None,
        navigating=False,
        motion=None,
    ):
        """Samples ``samples[0] .. samples[1] - 1`` of a frame of ``sample_count`` samples
        (``frame/sampling.py``), added to the samples this renderer already accumulated for
        it (a start of 0 begins the frame afresh), then the post stack on their filtered
        average. One sample of one is exactly the single-sample frame, with no accumulation.
        ``aux``: also write the depth, shadow and normal targets (a final render's passes;
        depth and normal are the centred sample's, shadow is averaged like colour).
        ``on_sample(done)`` after each sample; returning False stops the frame there (cancel).
        ``emission`` (with ``aux``): also write the Emission pass's target, averaged like colour.
        ``adaptive`` (``sampling.Adaptive``): what may end the frame early. Its Noise
        Threshold stops converged pixels (checked every few samples on the GPU; they are not
        shaded again) and ends the frame when every pixel has converged; its time limit ends
        it after the first sample that reaches it, counted from the first sample of this call
        unless ``deadline`` (a ``sampling.clock()`` value) says when. Neither looks at a clock
        when there is no time limit: a frame stays a function of the scene and its settings.
        ``navigating``: a one-sample frame while the view moves; its lights' maps keep the
        sizes a navigation frame planned at most NAVIGATION_REPLAN frames before (one fit per
        map, not two), and the frame after the view stops plans afresh. ``motion``
        (``motion.Motion``): what moves during the shutter; each sample of a multi-sample
        frame is drawn at its own time in it (motion blur).

        The frame's stages, in order: plan (``_plan``: what the frame draws, its lights and
        the world's, which lights move and their maps' sizes), then per sample the settle test
        once (``_settle``), the sample (``_sample_at``: shadow maps, lit pass, accumulate),
        then resolve (``_resolve``) and post (``_post``). Each takes the ``FramePlan`` and
        what it needs besides; none reads what an earlier call left on the renderer."""
        stats = FrameStats()
        clock = StageClock(self.wait_gpu if self.fence_stages else None)
        counters = (self._uploaded(), self.shaders.compiled, self.shaders.compile_seconds)
        self._clock = self.film.clock = clock
        with clock.stage("prepare"):
            frame = self._plan(
                snapshot, camera, settings, (width, height), aux, emission, sample_count, adaptive, stats
            )
            frame.motion = self._motion(motion, frame.accumulate, stats)
            self._plan_samples(frame, samples[0], adaptive, deadline, navigating, stats)
        drawn = None
        pixels = width * height
        for s in range(*samples):
            if frame.settle and s == 1:
                self._settle(frame, stats)
            if frame.accumulate and self.film.converged >= pixels:
                stats.stopped = "converged"  # every pixel settled, or a later call of a converged frame
                break
            drawn = self._sample_at(frame, s, stats)
            if frame.deadline is not None and frame.accumulate and not stats.stopped:
                self.film.finish()  # the sample's GPU work done, so the clock counts it
                if sampling.clock() >= frame.deadline:
                    stats.stopped = "time limit"
            if on_sample is not None and on_sample(s + 1) is False:
                stats.cancelled = True
                break
            if stats.stopped:
                break
        self.last_sample = drawn
        with clock.stage("resolve"):
            self._resolve(frame, drawn, stats)
        with clock.stage("post"):
            color, debug_image = self._post(frame, drawn, stats)
        stats.messages.extend(m for m in self.textures.messages() if m not in stats.messages)
        stats.cpu_seconds, stats.gpu_seconds = clock.cpu, clock.gpu
        stats.upload_bytes = self._uploaded() - counters[0]
        stats.shaders_compiled = self.shaders.compiled - counters[1]
        stats.compile_seconds = self.shaders.compile_seconds - counters[2]
        return self._output(frame, color, debug_image, stats)

    def _plan(self, snapshot, camera, settings, size, aux, emission, sample_count, adaptive, stats):
        """The plan stage: what the frame draws (the draw list, relative to the frame origin),
        the world's light (its SH light, directions per sample, light portals; none of them,
        nor ambient occlusion, where its light is under the frame's Noise Threshold), the lights
        it lights with and the film it draws into. Returns the ``FramePlan`` the later stages read."""
        width, height = size
        accumulate = sample_count > 1
        emission = bool(emission and aux)
        self.film.ensure(width, height, aux, emission)
        # The frame origin: the GPU gets every position relative to the camera (model matrices,
        # lights, the camera's and each map's view), computed here in float64, so a scene far
        # from the world origin keeps float32's precision where it is seen. Maps do not depend
        # on it (each is drawn and read through the same shift) and stay reusable when it moves.
        origin = camera.position if np.all(np.isfinite(camera.position)) else np.zeros(3)
        draws = draw_list(snapshot, self.batches, stats, origin, camera, settings, size)
        # A multi-sample frame's pixel offsets reach Filter Size pixels beyond the image, and
        # its points of the lens (depth of field) as far as its widest circle of confusion: its
        # maps and light bins are planned for what those samples see too.
        reach, lens = self._sample_reach(camera, draws, settings, size, accumulate, stats)
        self.shadow_pass.begin_frame(reach)
        stats.messages.extend(getattr(snapshot, "messages", ()))
        self.textures.forget(getattr(snapshot, "images_changed", ()))
        world = with_sh_light(snapshot.world, self.textures, self.shaders)
        if world is not snapshot.world:  # an Environment Texture's light, projected on the GPU
            snapshot = dataclasses.replace(snapshot, world=world, world_color=world.mean)
        world, sun = with_sun(snapshot.world)  # World > Settings > Sun: its light above the threshold
        if sun is not None:
            snapshot = dataclasses.replace(
                snapshot, world=world, world_color=world.mean, lights=[*snapshot.lights, sun]
            )
        threshold = adaptive.threshold if adaptive is not None and accumulate else 0.0
        negligible = world_negligible(snapshot.world if snapshot.world is not None else snapshot.world_color, threshold)
        directions, cones = (
            (0, [])
            if negligible
            else self._world_directions(snapshot, draws, settings, accumulate, camera, origin, stats)
        )
        room = MAX_LIGHTS - directions
        lights = select_lights(snapshot.lights, camera.position, room)
        if len(lights) < len(snapshot.lights):
            stats.messages.append(
                f"Penumbra: {len(snapshot.lights)} lights; only the {room} that contribute most to the view are lit"
            )
        return FramePlan(
            snapshot=snapshot,
            camera=camera,
            settings=settings,
            size=size,
            origin=origin,
            draws=draws,
            lights=lights,
            aux=aux,
            emission=emission,
            sample_count=sample_count,
            debug=DEBUG_VIEW[getattr(settings, "debug_view", "NONE")],
            directions=directions,
            cones=cones,
            world_negligible=negligible,
            reach=reach,
            lens_reach=lens,
        )

    @staticmethod
    def _sample_reach(camera, draws, settings, size, accumulate, stats):
        """Pixels beyond the image the frame's samples look: the pixel filter's reach and the
        lens's (``lens.lens_reach`` over the depths of what is drawn), in a multi-sample frame;
        0 for one sample, which looks through the pixel's and the lens's centres (said so in
        the report where the camera has depth of field). Returns (the whole reach, the lens's)."""
        if not accumulate:
            if camera.lens is not None:
                stats.messages.append(
                    "Penumbra: depth of field needs 2 or more samples: one sample is drawn through the lens's centre"
                )
            return 0.0, 0.0
        lens = 0.0
        if camera.lens is not None and draws:
            depths = lightspace.box_depth_range(camera.projection, camera.view, corners_of(draws), camera.is_ortho)
            lens = lens_reach(camera, depths, *size) if depths is not None else 0.0
        stats.lens_reach = lens
        return max(float(settings.filter_size), 0.0) + lens, lens

    @staticmethod
    def _motion(motion, accumulate, stats):
        """The frame's ``Motion`` where something moves and the frame has samples to spread
        over the shutter; a one-sample frame is drawn at the frame's time, and says so."""
        if motion is None or not motion.moves:
            return None
        if not accumulate:
            stats.messages.append(
                "Penumbra: motion blur needs 2 or more samples: one sample is drawn at the frame's time"
            )
            return None
        return motion

    def _world_directions(self, snapshot, draws, settings, accumulate, camera, origin, stats):
        """How many directions of the world's light each sample of the frame draws with maps
        (``world/directions.py``), and the cones that gather them: its light portals', or
        without portals the guide of an interior's openings (``world/probe.py``)."""
        # The world's light with visibility: a multi-sample frame adds ``world_samples``
        # directions of it per sample, each a sun with its own map.
        if not needs_directions(snapshot.world, settings):
            return 0, []
        # Light portals: the directions gather where the world's light enters what the camera
        # sees, and carry all of its light (no SH light on the surfaces of those samples). A
        # one-sample frame then takes its directions too: the SH light of a room's sky, even
        # occluded on screen, is nothing like the light through its windows.
        seen = [d for d in draws if d.instance.camera]
        if not seen:
            return (int(settings.world_samples) if accumulate else 0), []
        box = corners_of(seen).reshape(-1, 3)
        # The world's share of the light reaching what the camera sees (light_share).
        share = light_share(snapshot.world, snapshot.lights, 0.5 * (box.min(axis=0) + box.max(axis=0)))
        if getattr(snapshot, "portals", ()):
            cones = portal_cones(snapshot.portals, box.min(axis=0), box.max(axis=0))
        elif share >= PROBE_SHARE:
            # No light portal, and the world lights the frame: an interior's openings, found by
            # the world's probe, stand in for them.
            cones = self.world_probe.cones(
                draws, snapshot.world, camera.position, origin, self.shaders, self.materials, self.textures, stats
            )
            stats.world_guided = bool(cones)
        else:
            cones = []
        directions = int(settings.world_samples) if accumulate or cones else 0
        if directions and not cones:
            # The world's light costs what it adds: directions in proportion to its share.
            directions = directions_per_sample(share, directions)
        return directions, cones

    def _plan_samples(self, frame, start, adaptive, deadline, navigating, stats):
        """The rest of the plan stage: what may end the frame early, where its directions
        start, which lights move between its samples and the sizes of their maps (the frame's
        first plan; a later call of the same frame keeps the first call's), and the screen
        rectangles each light can reach."""
        film, settings, lights = self.film, frame.settings, frame.lights
        width, height = frame.size
        accumulate = frame.accumulate
        # A sample with ambient occlusion (a frame's first) takes no directions of the world:
        # the directions' sequence starts at the next one.
        if frame.directions and accumulate and frame.world_ao(0) is not None:
            frame.first_directions = 1
        # A lit debug view's values are not colour: no noise estimate of theirs ends a frame.
        frame.adaptive = adaptive if accumulate and not frame.debug.lit else None
        frame.noise = frame.adaptive is not None and frame.adaptive.threshold > 0.0
        # With depth of field, only where no blur reaches past the settle test's neighbourhood.
        frame.settle = (
            frame.motion is None  # a moving surface's pixels change with the sample's time
            and frame.adaptive is not None
            and frame.adaptive.settle > 0.0
            and flag_reach(settings.filter_size, frame.lens_reach) is not None
        )
        if not accumulate:
            film.converged = 0  # a single sample shades every pixel, whatever an earlier frame left
            # While the view moves, maps keep the sizes planned NAVIGATION_REPLAN frames ago.
            nav_key = (width, height, tuple(lt.use_shadow for lt in lights))
            last = self._navigation
            if navigating and last is not None and last[0] == nav_key and last[2] % NAVIGATION_REPLAN:
                self.shadow_pass.use_sizes(last[1])
                self._navigation = (nav_key, last[1], last[2] + 1)
            else:
                self._navigation = (nav_key, None, 1) if navigating else None
        else:
            # The NOISE view shows the estimate even where no threshold uses it.
            film.begin(
                frame.aux,
                frame.emission,
                fresh=start == 0,
                adaptive=frame.noise or frame.debug.id == "NOISE",
                settle=frame.settle,
                world_ratio=frame.world_ratio,
                gather_reach=sampling.gather_reach(settings.filter_size)
                if sampling.gathers(settings.filter_size)
                else 0,
            )
            # With map jitter every shadowed light changes from sample to sample (its maps'
            # texel grid), so lights with an extent are sampled on it however small their
            # penumbra.
            frame.jitter = bool(settings.shadow_map_jitter)
            # The frame's centred plan decides which lights move and the sizes of their maps;
            # a later call of the same frame (the viewport's next refinement: nothing changed,
            # or the frame would start afresh) keeps what the first call decided (a cache keyed
            # by what decides it).
            frame_key = (frame.sample_count, frame.jitter, tuple(lt.use_shadow for lt in lights))
            # With motion blur every sample plans its maps from its own scene (``_sample_at``):
            # the frame's centred plan says only which lights move.
            cached = self._frame_plan is not None and self._frame_plan[0] == frame_key
            if start > 0 and cached and frame.motion is None:
                frame.moving, sizes = self._frame_plan[1:]
                self.shadow_pass.use_sizes(sizes)
            else:
                first = self.shadow_pass.first_plan(frame.draws, lights, frame.camera, settings, film.size, True)
                frame.moving = sampling.sampled_lights(lights, first, every=frame.jitter)
                if frame.jitter:
                    frame.moving |= {i for i in first.lights if i < len(lights)}
                if frame.motion is None:
                    self.shadow_pass.keep_sizes(first, settings, lights)
                    self._frame_plan = (frame_key, frame.moving, self.shadow_pass.sizes)
        stats.lights_sampled = len(frame.moving)
        # Which part of the screen each light can reach: once a frame, padded by how far its
        # samples move it and by the camera's pixel offsets (light bins, lights out of view).
        if frame.motion is None:  # with motion blur each sample's own (``lights_in_view``)
            frame.rects = frame_light_rects(lights, frame.draws, frame.camera, width, height, frame.reach)
        if frame.adaptive is not None and frame.adaptive.time_limit > 0.0 and deadline is None:
            deadline = sampling.clock() + frame.adaptive.time_limit
        frame.deadline = deadline

    def _settle(self, frame, stats):
        """The settle stage, before a frame's second sample (settle.py): the pilot (the centred
        pixel with every light at its centre, whose maps the settle test reads), the settle
        test's variant of the lit pass over its surfaces, then the film's settle pass. Settled
        pixels take the pilot's value in place of the first sample's and take no more samples."""
        centred = [
            dataclasses.replace(lt, sampled=True, jittered=frame.jitter) if i in frame.moving else lt
            for i, lt in enumerate(frame.lights)
        ]
        pilot = SampleSpec(pilot=True, ao=frame.world_ao(0))
        centre = self._sample(frame, centred, frame.camera, stats, pilot)
        with self._clock.stage("settle"):
            test = SampleSpec(sample_count=frame.sample_count)
            target = self.film.settle_framebuffer()
            self._lit(frame, centre, FrameStats(), test, target)
            stats.pixels_settled = settle_pixels(
                self.film,
                frame.settings,
                frame.adaptive,
                frame.sample_count,
                frame.aux,
                frame.emission,
                frame.lens_reach,
            )

    def _sample_at(self, frame, s, stats):
        """Sample ``s`` of the frame: its pixel offset, its lights (moving ones at their point
        for ``s``, the world's directions), the sample itself (``_sample``), then its weight
        added to the film and, every few samples, the noise check (``stats.stopped``)."""
        film, settings, camera = self.film, frame.settings, frame.camera
        width, height = frame.size
        accumulate, count = frame.accumulate, frame.sample_count
        sample_start = self._clock.cpu_seconds
        draws, frame_lights = frame.draws, frame.lights
        with self._clock.stage("sample set-up"):
            if frame.motion is not None:
                # Motion blur: the sample's time in the shutter moves objects, lights and camera.
                u = motion_mod.sample_time(s, count, frame.motion.curve)
                moved = motion_mod.instances_at(frame.snapshot.instances, frame.motion, u)
                snapshot = dataclasses.replace(frame.snapshot, instances=moved)
                draws = draw_list(snapshot, self.batches, stats, frame.origin, camera, settings, frame.size)
                frame_lights = motion_mod.lights_at(frame.lights, frame.motion, u)
                camera = motion_mod.camera_at(camera, frame.motion, u)
                self.shadow_pass.begin_frame(frame.reach)  # this sample's maps from its own scene
            dx, dy, weight = sampling.pixel_offset(s, settings.filter_size) if accumulate else (0.0, 0.0, 1.0)
            # Depth of field: the sample looks from its point of the lens (lens.py).
            view_camera = lens_camera(camera, lens_offset(s, camera.lens)) if accumulate and camera.lens else camera
            if dx or dy:
                jittered = sampling.jittered_projection(view_camera.projection, dx, dy, width, height)
                view_camera = dataclasses.replace(view_camera, projection=jittered)
            lights = [
                sampling.light_at_sample(lt, i, s, count, frame.jitter, progressive=frame.noise)
                if i in frame.moving
                else lt
                for i, lt in enumerate(frame_lights)
            ]
            if frame.directions and s >= frame.first_directions:
                index = (s - frame.first_directions) * frame.directions
                lights += world_lights(frame.snapshot.world, index, frame.directions, cones=frame.cones)
                stats.world_directions += frame.directions
        spec = SampleSpec(
            alpha_offset=(s + 0.5) / count if accumulate else 0.5,
            sample_count=count if accumulate else 1,
            ao=frame.world_ao(s),
            index=s,
        )
        drawn = self._sample(frame, lights, view_camera, stats, spec, draws, camera)
        with self._clock.stage("accumulate"):
            if accumulate:
                stats.pixel_samples_skipped += film.converged
                gather = sampling.gather_uniforms(dx, dy, settings.filter_size)  # the gathering film
                film.accumulate(weight, frame.aux, frame.emission, s, gather)
            if frame.aux and accumulate and s == 0:  # the centred sample's depth and normal
                film.keep_centre()
            stats.samples += 1
            # (No check after a frame's last sample: it ends there anyway.)
            adaptive = frame.adaptive
            last = s + 1 == count
            if frame.noise and not last and adaptive.checks_at(s + 1):
                if film.check(adaptive.threshold) >= width * height:
                    stats.stopped = "converged"
        stats.sample_cpu_seconds.append(self._clock.cpu_seconds - sample_start)
        return drawn

    def _resolve(self, frame, drawn, stats):
        """The resolve stage: the film's accumulation divided by its weights; the batches the
        frame did not use let go; a navigation frame that planned afresh keeps its map sizes."""
        film = self.film
        stats.pixels_converged = film.converged if frame.accumulate else 0
        if frame.accumulate and stats.samples:
            film.resolve(frame.aux, frame.emission)
        self.batches.keep({(key, geo.serial) for key, geo in frame.snapshot.geometry.items()})
        nav = self._navigation
        plan = drawn.plan if drawn is not None else None
        if nav is not None and nav[1] is None and plan is not None:  # a navigation frame that planned afresh
            sizes = frame_sizes(plan, max(1, int(frame.settings.shadow_map_size)))
            self._navigation = (nav[0], sizes, nav[2])

    def _post(self, frame, drawn, stats):
        """The post stage: the post stack on the resolved image, or a debug view instead of
        both; the frame's memory in ``stats``. Returns (colour texture, debug image or None)."""
        film, settings = self.film, frame.settings
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
            + (self.world_ao.memory_bytes if stats.ao_prepasses else 0)
        )
        return color, debug_image

    def _output(self, frame, color, debug_image, stats):
        """The frame's ``FrameOutput``: its image and, with ``aux``, its passes."""
        film = self.film
        width, height = frame.size
        if not frame.aux:
            out = FrameOutput(color, None, None, stats, width, height, lit=film.color)
            out.debug = debug_image
            return out
        out = FrameOutput(color, film.depth, film.shadow, stats, width, height, lit=film.color, normal=film.normal)
        out.debug = debug_image
        out.emission = film.emission if frame.emission else None
        if frame.accumulate and film.centre is not None:
            out.depth_data, out.normal_data = film.centre
        return out

    def _sample(self, frame, lights, view_camera, stats, spec, draws=None, camera=None):
        """One sample (``spec``, a ``SampleSpec``) of ``frame`` with ``lights``: shadow maps
        (planned from the unjittered ``camera``, the frame's unless given, so a light that does
        not move between samples keeps its map), then the lit pass seen through ``view_camera``,
        of ``draws`` (the frame's unless given: a motion-blurred sample's own). With ``spec.ao``
        the camera depth prepass of the world's ambient occlusion is drawn first through the lit
        pass's raster camera (``world/occlusion.py``). Returns what it drew (``SampleResult``)."""
        film = self.film
        draws = frame.draws if draws is None else draws
        camera = frame.camera if camera is None else camera
        width, height = film.size
        lights, rects = lights_in_view(lights, draws, view_camera, width, height, stats, frame.rects)
        self._clock.begin("shadow pass")
        plan = self.shadow_pass.draw(
            draws,
            lights,
            camera,
            frame.settings,
            film.size,
            stats,
            self.shaders,
            self.materials,
            self.textures,
            self.batches,
            frame.origin,
            spec.alpha_offset,
        )
        self._clock.end()
        depth_range = self.shadow_pass.depth_range
        if depth_range is UNSET:  # no shadow plan this frame: the quick, wider bound
            depth_range = lightspace.box_depth_range(camera.projection, camera.view, corners_of(draws), camera.is_ortho)
        # The lit pass rasterises with the depth buffer spread over what the camera sees.
        fitted = lightspace.depth_fitted(view_camera.projection, view_camera.is_ortho, depth_range)
        raster_camera = (
            view_camera if fitted is view_camera.projection else dataclasses.replace(view_camera, projection=fitted)
        )
        result = SampleResult(lights, plan, (raster_camera, view_camera, rects), draws=draws)
        if spec.ao is not None:
            with self._clock.stage("world ao"):
                self.world_ao.draw(
                    draws,
                    raster_camera,
                    film.size,
                    frame.origin,
                    self.shaders,
                    self.materials,
                    self.textures,
                    stats,
                    spec.alpha_offset,
                )
        with self._clock.stage("lit pass"):
            result.data = self._lit(frame, result, stats, spec)
        stats.binned = result.data.bins is not None
        return result

    def _lit(self, frame, sample, stats, spec, target=None):
        """The lit pass of ``sample`` (a ``SampleResult``: its lights, the maps of its plan, its
        cameras and light rectangles), for sample ``spec`` (``SampleSpec``; its ``ao`` over the
        prepass just drawn); ``target``: the settle test's framebuffer (the ``SETTLE_TEST``
        variant drawn into it, ``settle.py``; never occluded). Returns the frame data it drew
        with."""
        ao = spec.ao if target is None else None
        film, snapshot, settings = self.film, frame.snapshot, frame.settings
        aux = frame.aux and target is None
        lights, plan = sample.lights, sample.plan
        raster_camera, view_camera, rects = sample.cameras
        atlas = self.shadows if plan is not None and plan.tiles else None
        data = build_frame_data(
            lights,
            raster_camera,
            snapshot.world if snapshot.world is not None else snapshot.world_color,
            settings,
            plan,
            tile_size=atlas.size if atlas else 1,
            atlas_columns=atlas.columns if atlas else 1,
            depth_format=atlas.depth_format if atlas else "FLOAT32",
            aux_outputs=aux,
            rects=rects,
            size=film.size,
            alpha_offset=spec.alpha_offset,
            origin=frame.origin,
            sample_count=spec.sample_count,
            settle=target is not None,
            pilot=spec.pilot,
            world_sampled=frame.world_sampled,
            world_sh=frame.world_sh or not any(lt.world for lt in lights),
            world_ao=ao,
            sample_index=spec.index,
            rsm=atlas is not None and atlas.rsm,
            world_ratio=frame.world_ratio,
        )
        seen = [d for d in (sample.draws if sample.draws is not None else frame.draws) if d.instance.camera]
        masks = light_masks(seen, lights, data.order) if data.defines.get("LIGHT_LINKING") else None
        world = (snapshot.world, snapshot.world_color)
        if target is not None:
            self.lit_pass.draw_settle_test(film, seen, view_camera, data, atlas, stats, frame.origin, masks, target)
        else:
            passes = (settings, aux, frame.emission, stats, frame.origin, masks)
            self.lit_pass.draw(film, seen, view_camera, data, atlas, world, *passes, ao=self.world_ao if ao else None)
        return data

    def _debug_view(self, view, accumulate, settings, last, occluded=False):
        """The debug view ``view`` of the frame just rendered (``debug_view.DebugImage``);
        ``last``: its last sample (``SampleResult``: the SHADOW_MAPS view's plan and lights);
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
        return self.lit_pass.uploaded + self.shadows.uploaded + self.materials.uploaded + self.batches.uploaded

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
        """Give the frame's targets and the shadow atlas back to the pool: at the end of a
        final render, inside its GPU context. The renderer is not used again."""
        if self.pool is None:
            return
        self.film.release()
        self.shadows.free()
        self.world_ao.release()
        self.world_probe.release()
