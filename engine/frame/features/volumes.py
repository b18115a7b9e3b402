"""Light through air: a World › Volume and the interiors of meshes whose material has a Volume
output (``scene/volumes.py``: homogeneous media, Cycles' coefficients), drawn as Cycles draws
single scattering (Volume Bounces 0).

Two parts, both over the media block (``MEDIUM_STRUCT``, lib/volumes.glsl):

* **The lit pass** (its part ``VOLUMES``): each light's light on a surface is multiplied by what
  the media let through between the surface and the light, exactly (homogeneous media: the
  optical depth is each medium's extinction times the length of the segment inside it).
* **The march** (``MARCH``, after each sample's lit pass): along each pixel's ray from the
  camera's clip start to the surface in the z-buffer (or the clip end), the light every lamp
  scatters towards the camera through its own shadow map (Henyey-Greenstein phase, the lamp's
  Volume factor, the media's transmittance to it), the world's SH light convolved with the
  phase, and the media's emission, weighted by the transmittance from the camera. The steps'
  points are drawn anew each sample (``settings.volume_samples`` steps), so a frame's samples
  converge to the integral. The surface's colour is then multiplied by the ray's transmittance
  and the scattered light added (two blended copies into the film's colour).

A WORLD medium fills the sphere of the camera's clip end around it (what the view holds, as in
EEVEE; Cycles' fills all space). A mesh's medium fills its bounding box (named where the mesh
is not a box). Wanted only where the scene has a medium: a frame without one pays nothing and
draws as before.

Approximate (said once in the report): single scattering only; the world's light in the media
is not shadowed by surfaces (only by the media, along one direction per step and sample);
alpha-blended surfaces take the fog of what is behind them; light passes and Emission hold no
volume light (Cycles' Volume Direct is not written); reflections and refractions do not show
the media."""

import math

import numpy as np

from ....shaders.loader import Program, ProgramPart, Struct
from ...gpu_pool import new_texture
from ...shadows import lightspace
from ...shadows.planning import MAX_SHADOW_TILES
from ..film_programs import SCALED_COPY
from ..programs import FRAME_STRUCT, LIGHT_STRUCT, LIT, MAX_LIGHTS, SHADOW_SAMPLER, TILE_STRUCT
from .base import Feature, LitPart

MAX_MEDIA = 8
VOLUME_TERM = 3  # the Volume Light debug view's DEBUG_TERM: surfaces write 0, the march adds its light
MEDIUM_KIND = {"WORLD": 0, "BOX": 1}

MEDIUM_STRUCT = Struct(
    "MediumData",
    (
        ("MAT4", "to_unit"),  # world positions (relative to the frame origin) -> the box's [-1, 1]^3
        ("VEC3", "extinction"),  # scattering + absorption, per unit of length
        ("INT", "kind"),  # MEDIUM_WORLD or MEDIUM_BOX
        ("VEC3", "scatter"),  # per unit of length
        ("FLOAT", "anisotropy"),  # Henyey-Greenstein g
        ("VEC3", "emission"),  # radiance per unit of length
        ("FLOAT", "unused"),
    ),
)

# The lit program's part: each light through the media (lib/lit_lights.glsl).
PART = ProgramPart(
    "volumes",
    libs=("lib/volumes.glsl",),
    uniform_blocks=((MEDIUM_STRUCT, "media", MAX_MEDIA),),
    defines=(("VOLUMES", True),),
)

DEPTH_SAMPLER = "scene_depth"

# The march over the pixels (shaders/volume_march.frag.glsl): the lit pass's libraries of
# lights, shadow filters and the world's SH light, with the lit program's defaults for what
# they switch on; the sample's variant gives the filters and the atlas's format.
MARCH = Program(
    name="volume_march",
    vertex="fullscreen.vert.glsl",
    fragment="volume_march.frag.glsl",
    libs=("lib/volumes.glsl", "lib/lights.glsl", "lib/shadow_filters.glsl", "lib/world_sh.glsl", "lib/material.glsl"),
    vertex_in=(("VEC2", "pos"),),
    push_constants=(("VEC2", "viewport_size"),),
    samplers=(("FLOAT_2D", SHADOW_SAMPLER), ("FLOAT_3D", "jitter_tex"), ("FLOAT_2D", DEPTH_SAMPLER)),
    uniform_blocks=(
        (FRAME_STRUCT, "frame", 0),
        (LIGHT_STRUCT, "lights", MAX_LIGHTS),
        (TILE_STRUCT, "shadow_tiles", MAX_SHADOW_TILES),
        (MEDIUM_STRUCT, "media", MAX_MEDIA),
    ),
    outputs=(("VEC4", "out_transmit"), ("VEC4", "out_scatter")),
    defines=(*LIT.defines, ("VOLUMES", True)),
)

TARGET_FORMAT = "RGBA32F"

APPROXIMATE = (
    "Penumbra: volumes are drawn with single scattering (as Cycles with Volume Bounces 0); the world's light "
    "in them is not shadowed by surfaces, and reflections, refractions and alpha-blended surfaces do not show them"
)


MIN_STEPS = 8  # a sample's steps at least


def march_steps(frame):
    """Steps of one sample's march: the frame's Steps (``settings.volume_samples``) spread over
    its samples, MIN_STEPS at least. Each sample draws its steps' points anew, so the frame's
    points together sample the ray as densely as Steps would in every sample."""
    steps = max(int(frame.settings.volume_samples), 1)
    samples = max(int(frame.sample_count), 1) if frame.accumulate else 1
    return max(min(MIN_STEPS, steps), math.ceil(steps / samples))


def clip_end(camera):
    """The distance of the camera's far clip plane along its axis (``projection``'s)."""
    p = np.asarray(camera.projection, np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        far = (p[2, 3] - 1.0) / p[2, 2] if camera.is_ortho else p[2, 3] / (p[2, 2] + 1.0)
    far = abs(float(far))
    return far if math.isfinite(far) and far > 0.0 else 1.0e6


def medium_row(medium, origin):
    """The ``MEDIUM_STRUCT`` row of ``medium`` (``scene.volumes.Medium``) for positions
    relative to ``origin``."""
    to_unit = np.eye(4)
    if medium.kind == "BOX":
        to_unit = np.linalg.inv(np.asarray(medium.matrix, np.float64)) @ lightspace.from_origin(origin)
    return {
        "to_unit": to_unit,
        "extinction": medium.extinction,
        "kind": MEDIUM_KIND[medium.kind],
        "scatter": medium.scatter,
        "anisotropy": float(medium.anisotropy),
        "emission": medium.emission,
        "unused": 0.0,
    }


# Corner i of a box at bits x, y, z of i (as ``draw_list.corners_of``), of [-1, 1]^3.
UNIT_CORNERS = np.array([[(i & 1) * 2 - 1, (i >> 1 & 1) * 2 - 1, (i >> 2 & 1) * 2 - 1, 1] for i in range(8)], float)


def media_receivers(media, camera, draws):
    """The boxes (n, 8, 3 world corners) the media fill, for the lights and their maps to
    reach (``FramePlan.receivers``): each box medium's; for the world's, the camera's view from
    its clip start to the farthest drawn point (or its clip end without draws)."""
    boxes = [(np.asarray(m.matrix, np.float64) @ UNIT_CORNERS.T).T[:, :3] for m in media if m.kind == "BOX"]
    if any(m.kind == "WORLD" for m in media):
        view = view_box(camera, draws)
        if view is not None:
            boxes.append(view)
    boxes = [b for b in boxes if np.all(np.isfinite(b))]
    return np.stack(boxes) if boxes else None


def view_box(camera, draws):
    """The camera's view from its clip start to the farthest corner of the draws along its
    axis (at most its clip end): 8 world corners, or None."""
    inverse = lightspace.finite_inverse(camera.projection @ camera.view)
    if inverse is None:
        return None
    ndc = np.array([[(i & 1) * 2 - 1, (i >> 1 & 1) * 2 - 1, -1.0, 1.0] for i in range(4)])
    near = ndc @ inverse.T
    far_ndc = ndc.copy()
    far_ndc[:, 2] = 1.0
    far = far_ndc @ inverse.T
    near, far = near[:, :3] / near[:, 3:], far[:, :3] / far[:, 3:]
    forward, position = camera.forward, camera.position
    start, end = float(np.dot(near[0] - position, forward)), float(np.dot(far[0] - position, forward))
    reach = end
    if draws:
        corners = np.concatenate([d.corners for d in draws])
        reach = min(end, max(float(np.max((corners - position) @ forward)), start))
    f = (reach - start) / (end - start) if end > start else 1.0
    return np.concatenate([near, near + (far - near) * f])


def media_block(media, origin):
    """The ``media`` block of at most MAX_MEDIA media: (packed bytes, how many)."""
    media = [m for m in media if not m.empty][:MAX_MEDIA]
    return MEDIUM_STRUCT.pack([medium_row(m, origin) for m in media], MAX_MEDIA), len(media)


def _bound(lit, name, raw):
    """The lit pass's uniform block ``name`` where its draws left ``raw`` in it (this sample's),
    else ``raw`` uploaded."""
    block = lit._ubos.holding(name, raw.tobytes())
    return block if block is not None else lit._ubo(name, raw)


class Volumes(Feature):
    name = "volumes"

    def __init__(self, renderer):
        super().__init__(renderer)
        self._targets = None  # (transmittance, scattered light, their framebuffer) at the film's size
        self._onto = None  # (the film's colour target, a framebuffer of it alone)
        self._block = None
        self._params = (0.0, 0.0, 0.0)

    def wanted(self, frame):
        return any(not m.empty for m in getattr(frame.snapshot, "media", ()))

    def plan(self, frame):
        media = [m for m in frame.snapshot.media if not m.empty]
        stats = frame.stats
        if len(media) > MAX_MEDIA:
            stats.messages.append(f"Penumbra: {len(media)} volumes; only the first {MAX_MEDIA} are drawn")
        self._block, count = media_block(media, frame.origin)
        self._params = (float(count), clip_end(frame.camera), float(march_steps(frame)))
        frame.unsettled = True  # every pixel the media cover changes from sample to sample
        frame.receivers = media_receivers(media, frame.camera, frame.draws)
        if APPROXIMATE not in stats.messages:
            stats.messages.append(APPROXIMATE)

    def _part(self, frame, sample):
        rows = {"volume_params": (*self._params, float(sample.alpha_offset))}
        cameras = getattr(sample, "cameras", None)
        if cameras is not None:
            shift = lightspace.from_origin(frame.origin)
            raster, view = cameras[0], cameras[1]
            for name, camera in (("volume_inv_raster", raster), ("volume_inv_view", view)):
                inverse = lightspace.finite_inverse(camera.projection @ camera.view @ shift)
                rows[name] = inverse if inverse is not None else np.eye(4)
        return LitPart(program=PART, rows=rows, blocks={"media": self._block})

    def lit(self, frame, sample):
        return self._part(frame, sample)

    def capture(self, frame, sample):
        return self._part(frame, sample)  # what a probe's view shows is lit through the media too

    def after_lit(self, frame, sample):
        if (frame.debug.lit and frame.debug.term != VOLUME_TERM) or sample.data is None:
            return  # a lit debug view's values are not light (the Volume Light view's surfaces are 0)
        import gpu

        renderer = self.renderer
        film, lit = renderer.film, renderer.lit_pass
        width, height = film.size
        transmit, scatter, fb = self._ensure(width, height)
        data = sample.data
        atlas = sample.atlas
        tiles = atlas.tiles_block(data.tiles) if atlas is not None else None
        # The blocks the sample's lit pass bound last (its own frame, lights and tiles): bound
        # again, not uploaded again.
        blocks = {
            "frame": _bound(lit, "frame", data.frame),
            "lights": _bound(lit, "lights", data.lights),
            "shadow_tiles": tiles if tiles is not None else _bound(lit, "tiles", data.tiles),
            "media": _bound(lit, "media", self._block),
        }
        samplers = {
            SHADOW_SAMPLER: atlas.texture if atlas is not None else lit._shadow_dummy(),
            "jitter_tex": lit._jitter(data.disk_samples),
            DEPTH_SAMPLER: film.zbuffer,
        }
        defines = {**data.defines, "VOLUMES": True, "DEBUG_LIT": False, "DEBUG_TERM": 0}
        uniforms = {"viewport_size": (float(width), float(height))}
        with frame.clock.stage("volumes"):
            film.fullscreen(MARCH, fb, samplers, uniforms, blocks=blocks, defines=defines)
            onto = self._colour_framebuffer(film)
            # What is behind times the media's transmittance, then the light they add.
            film.fullscreen(SCALED_COPY, onto, {"src_color": transmit}, {"scale": 1.0}, blend="MULTIPLY")
            film.fullscreen(SCALED_COPY, onto, {"src_color": scatter}, {"scale": 1.0}, blend="ADDITIVE_PREMULT")
        gpu.state.blend_set("NONE")
        frame.stats.passes += 1

    def _ensure(self, width, height):
        import gpu

        if self._targets is not None and self._targets[0].width == width and self._targets[0].height == height:
            return self._targets
        self.release()
        pool = self.renderer.pool
        transmit = new_texture(pool, (width, height), TARGET_FORMAT)
        scatter = new_texture(pool, (width, height), TARGET_FORMAT)
        self._targets = (transmit, scatter, gpu.types.GPUFrameBuffer(color_slots=(transmit, scatter)))
        return self._targets

    def _colour_framebuffer(self, film):
        import gpu

        if self._onto is None or self._onto[0] is not film.color:
            self._onto = (film.color, gpu.types.GPUFrameBuffer(color_slots=(film.color,)))
        return self._onto[1]

    def memory_bytes(self, frame):
        if self._targets is None:
            return 0
        return 2 * self._targets[0].width * self._targets[0].height * 16

    def release(self):
        if self._targets is not None and self.renderer.pool is not None:
            self.renderer.pool.give(list(self._targets[:2]))
        self._targets = None
        self._onto = None
