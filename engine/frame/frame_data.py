"""The lit pass's uniform data for one frame, built in numpy: no bpy, no gpu.

``build_frame_data`` turns the snapshot's lights, the camera, the settings and the shadow plan
into the packed uniform blocks and shader defines the lit pass binds, so what a frame sends
to the GPU is unit-tested without one.
"""

import math
from dataclasses import dataclass, field
from functools import cached_property, lru_cache

import numpy as np

from ..enums import DEBUG_VIEW, LIGHT_TYPE, SHADOW_FILTER, SHADOW_MODE
from ..shadows import kernels, light_bins, lightspace
from ..shadows.kernels import RING
from .programs import (
    FRAME_STRUCT,
    LIGHT_STRUCT,
    LIGHT_WORDS,
    MAX_DISK_SAMPLES,
    MAX_LIGHTS,
    LitVariant,
    max_filter_radius,
    packed_tiles,
)

_ZERO = np.zeros(3)  # the default frame origin: world space as it is


@dataclass
class FrameData:
    frame: np.ndarray  # FRAME_STRUCT, packed
    lights: np.ndarray  # MAX_LIGHTS x LIGHT_STRUCT
    tiles: np.ndarray  # MAX_SHADOW_TILES x TILE_STRUCT
    variant: LitVariant  # the lit pass's variant, typed
    disk_samples: int  # jittered-disk samples the variant reads (0: it reads none)
    order: list  # the light index of each row of ``lights`` (shadowed lights first)
    bins: np.ndarray = None  # (rows, columns, LIGHT_WORDS) light masks of the screen bins, or None
    samplers: dict = field(default_factory=dict)  # {name: texture} the techniques' parts bind
    blocks: dict = field(default_factory=dict)  # {name: packed bytes} their uniform blocks (``LitPart.blocks``)
    begins: tuple = ()  # the techniques' GPU work over the frame block before the draws (``LitPart.begin``)
    betweens: tuple = ()  # their work after the opaque surfaces, before the transmissive (``LitPart.between``)
    # The techniques' ``ProgramPart`` values of the lit program (``LitPart.program``), in order,
    # and those blended surfaces take: what a ``programs.LitKey`` lists after the pass's own.
    parts: tuple = ()
    blended_parts: tuple = ()

    @cached_property
    def defines(self):
        """The variant's defines (``LitVariant.defines``), made once."""
        return self.variant.defines()


def disk_samples(settings, sample_count=1):
    """Disk taps per sample: ``shadow_samples`` rounded down to whole rings, within [RING,
    MAX_DISK_SAMPLES]. A frame of ``sample_count`` samples spreads them over its samples (each
    sample reads its own rotation of the per-pixel disk, ``shadow_filters.glsl``
    ``disk_sample``), at least one ring per sample: the frame reads at least as many taps per
    pixel as a one-sample frame, and a sample pays only for its share."""
    per_sample = int(settings.shadow_samples) // max(1, int(sample_count))
    return min(max(per_sample // RING * RING, RING), MAX_DISK_SAMPLES)


def indirect_samples(settings):
    """Reflective shadow-map texels each pixel gathers per light and sample, with Light Paths
    > Diffuse Bounces at 1 (0: no bounce)."""
    if int(getattr(settings, "indirect_bounces", 0)) < 1:
        return 0
    return int(np.clip(int(getattr(settings, "indirect_samples", 16)), 1, 256))


def select_lights(lights, camera_position, limit):
    """At most ``limit`` lights, the ones whose light reaches the camera's surroundings most
    (sun: its strength; others: power over the squared distance to the camera), in their
    original order. Ties keep the earlier light, so the choice is stable across frames."""
    if len(lights) <= limit:
        return list(lights)
    cam = np.asarray(camera_position, np.float64)

    def strength(light):
        power = float(np.dot(light.color, (0.2126, 0.7152, 0.0722)))
        if light.type == "SUN":
            return power
        d2 = float(np.sum((light.position - cam) ** 2)) + light.radius**2
        return power / (4.0 * math.pi * max(d2, 1e-12))

    order = sorted(range(len(lights)), key=lambda i: (-strength(lights[i]), i))
    keep = sorted(order[:limit])
    return [lights[i] for i in keep]


def light_row(light, shadow=None, origin=_ZERO):
    """One LIGHT_STRUCT row. ``shadow``: the light's ``shadows.LightShadow`` or None;
    ``origin``: the frame origin, which positions are given relative to."""
    half = 0.5 * min(max(light.spot_size, 0.0), math.pi)
    cos_half = math.cos(half)
    tiles = (list(shadow.tiles) if shadow else []) + [-1] * 6
    right, up, (scale_x, scale_y) = light.spot_axes if light.type == "SPOT" else ((1, 0, 0), (0, 1, 0), (1, 1))
    return {
        "color": light.color,
        "type": LIGHT_TYPE.value(light.type),
        "position": np.asarray(light.position, np.float64) - origin,
        "radius": light.radius,
        "direction": light.direction,
        "spot_cos_half": cos_half if light.type == "SPOT" else -2.0,
        "spot_blend_width": (1.0 - cos_half) * max(light.spot_blend, 0.0),
        "spot_right": right,
        "spot_scale_x": scale_x,
        "spot_up": up,
        "spot_scale_y": scale_y,
        "shadow_mode": SHADOW_MODE.value(shadow.mode if shadow else "NONE"),
        "shadow_radius": light.shadow_radius * light.penumbra_scale,
        "sun_tan_half_angle": math.tan(0.5 * min(max(light.angle, 0.0), math.pi * 0.99)) * light.penumbra_scale,
        "tiles": tiles[:4],
        "tiles_45": tiles[4:6],
        "bias_scale": light.bias_scale,
        "diffuse_factor": light.diffuse_factor,
        "specular_factor": light.specular_factor,
        "volume_factor": getattr(light, "volume_factor", 1.0),
        "jittered": int(light.jittered),
        "offset_scale": light.offset_scale,
        "cascade_splits": (list(shadow.splits) + [3.0e38] * 4)[:4] if shadow and shadow.splits else (3.0e38,) * 4,
        "cascade_blend": (list(shadow.blend) + [0.0] * 4)[:4] if shadow and shadow.blend else (0.0,) * 4,
        "world": int(light.world),
    }


def kept_light_row(kept, light, shadow=None, origin=_ZERO):
    """``light_row(light, shadow, origin)``, taken from ``kept`` (a dict kept for one frame, or
    None) when the same light object, with maps in the same tiles, made it before around the
    same origin: a light that does not move between a frame's samples is the same object in
    each (``Renderer.sample``), so its row is made once a frame, not once a sample."""
    if kept is None:
        return light_row(light, shadow, origin)
    where = None if shadow is None else (shadow.mode, tuple(shadow.tiles), tuple(shadow.splits), tuple(shadow.blend))
    key = (id(light), id(origin), where)
    entry = kept.get(key)
    if entry is None or entry[0] is not light or entry[1] is not origin:  # an id reused by another object
        entry = kept[key] = (light, origin, light_row(light, shadow, origin))
    return entry[2]


_ZERO4 = (0.0, 0.0, 0.0, 0.0)
_ZERO44 = (_ZERO4,) * 4
_EYE44 = ((1.0, 0.0, 0.0, 0.0), (0.0, 1.0, 0.0, 0.0), (0.0, 0.0, 1.0, 0.0), (0.0, 0.0, 0.0, 1.0))

# The frame row's fields that take the same value in every frame until a technique's part sets
# them (``LitPart.rows``): immutable values, so the template is shared and each row a copy.
_FRAME_DEFAULTS = {
    "shadowed_count": 0,
    "shadowed_mask": _ZERO4,
    "sampled_count": 0,
    "sampled_mask": _ZERO4,
    "alpha_offset": 0.5,
    **{f"world_sh{k}": _ZERO4 for k in range(1, 9)},
    "ao_projection": _ZERO4,
    "ao_projection_w": _ZERO4,
    "ao_viewport": (1.0, 1.0),
    "ao_distance": 0.0,
    "ao_jitter": (0.0, 0.0),
    "sample_index": 0,
    "lens_coc": _ZERO4,
    "env_rotation_x": (1.0, 0.0, 0.0, 0.0),
    "env_rotation_y": (0.0, 1.0, 0.0, 0.0),
    "env_rotation_z": (0.0, 0.0, 1.0, 0.0),
    "env_params": _ZERO4,
    "ssr_params": _ZERO4,
    "refr_params": _ZERO4,
    "planar_influence": _ZERO44,
    "planar_plane": (0.0, 0.0, 1.0, 0.0),
    "planar_params": _ZERO4,
    "clip_plane": (0.0, 0.0, 0.0, 1.0),
    "cube_params": _ZERO4,
    "cube_probe": (0.0, 0.0, 0.0, -1.0),
    "cube_probe_influence": _ZERO44,
    "cube_probe_shape": _ZERO4,
    "cube_camera": (0.0, 0.0, 0.0, -1.0),
    "volume_params": _ZERO4,
    "volume_inv_view": _EYE44,
    "volume_inv_raster": _EYE44,
}


def frame_row(camera, world_color, light_count, settings, tile_size, atlas_columns, origin=_ZERO):
    view = camera.view @ lightspace.from_origin(origin)  # takes positions relative to ``origin``
    view_proj = camera.projection @ view
    row = dict(_FRAME_DEFAULTS)
    row.update(
        {
            "view_proj": view_proj,
            "view": view,
            "camera_position": camera.position - origin,
            "is_ortho": int(camera.is_ortho),
            "camera_forward": camera.forward,
            "light_count": light_count,
            "world_color": np.asarray(world_color, np.float64)[:3],
            "constant_bias": settings.shadow_bias,
            "slope_bias": settings.shadow_slope_bias,
            "normal_offset": settings.shadow_normal_offset,
            "receiver_plane": int(bool(settings.shadow_receiver_plane)),
            "pcf_spacing": settings.pcf_spacing,
            "filter_radius": settings.shadow_filter_radius,
            "max_filter_radius": max_filter_radius(tile_size),
            "tile_size": tile_size,
            "atlas_columns": atlas_columns,
            "ssr_view": view,
            "ssr_view_proj": view_proj,
            "planar_view": view,
            "planar_view_proj": view_proj,
        }
    )
    return row


def shading_order(lights, plan):
    """Light indices as the lit pass loops over them: lights sampled over their extent with a
    map first, then the other lights with a map, then the rest (each group in its own order).
    The lit pass runs a shadow filter only in its first two loops, so a light without a map
    never pays for one. A direction of the world's light without a map (nothing casts a
    shadow from it) stays: it adds its unblocked light to both of the world ratio's sums.
    Returns (order, number sampled, number with maps)."""
    mapped = [i for i in range(len(lights)) if i in plan.lights]
    sampled = [i for i in mapped if lights[i].sampled]
    others = [i for i in mapped if not lights[i].sampled]
    rest = [i for i in range(len(lights)) if i not in plan.lights]
    return sampled + others + rest, len(sampled), len(mapped)


def _debug_lit(settings):
    """Whether the lit pass writes a lit debug view's values (not a term of its colour)."""
    view = DEBUG_VIEW[getattr(settings, "debug_view", "NONE")]
    return view.lit and not view.term


@dataclass(frozen=True)
class AtlasShape:
    """The shadow atlas a plan was drawn into: its tiles' size in texels, its columns and its
    depth format (1, 1, FLOAT32 when no map was drawn)."""

    tile_size: int = 1
    columns: int = 1
    depth_format: str = "FLOAT32"


@dataclass(frozen=True)
class LitInputs:
    """What one sample's lit pass is drawn for, besides its lights, camera, world, settings
    and shadow plan (``build_frame_data``): one field each, with its default.

    ``atlas``: the ``AtlasShape`` the plan was drawn into; ``aux_outputs``: the variant writes
    the depth, shadow and normal targets as well as colour; ``rects``: per light, the screen
    rectangle it can light (``light_bins.screen_rects``) on a frame of ``size`` (width,
    height) pixels, which bins the lights when several are local; ``alpha_offset``: the
    sample's shift of the alpha-hash threshold ((s + 0.5) / N); ``origin``: the frame origin
    (every position the GPU gets is relative to it); ``sample_count``: the frame's samples,
    which share the disk filters' taps; ``sample_index``: this sample's index in its frame;
    ``world_sampled``: the frame samples the world's light with shadow maps (its settle test
    weighs the world's light), whether or not this sample's directions have maps;
    ``world_sh``: the surfaces take the world's SH light (False: this sample's directions of
    the world carry all of it, ``world.directions.world_lights`` with portals); ``parts``: the
    frame's techniques' ``features.LitPart`` of this sample (parts of the lit program, rows of
    the frame block, samplers); ``light_rows``: a dict the caller keeps for one frame, where a
    light that does not move between its samples keeps its row (``kept_light_row``)."""

    atlas: AtlasShape = AtlasShape()
    aux_outputs: bool = True
    rects: object = None
    size: tuple | None = None
    alpha_offset: float = 0.5
    origin: object = None  # None: world space as it is
    sample_count: int = 1
    sample_index: int = 0
    world_sampled: bool = False
    world_sh: bool = True
    parts: tuple = ()
    light_rows: dict | None = field(default=None, compare=False)


@lru_cache(maxsize=16)
def _pcf_weights(size):
    """``kernels.pcf_weights`` as the floats a variant holds (the lit pass compiles them in)."""
    return tuple(float(w) for w in kernels.pcf_weights(size))


def build_frame_data(lights, camera, world_color, settings, plan, inputs=LitInputs()):
    """Everything the lit pass binds for this sample. ``lights``: at most MAX_LIGHTS snapshot
    lights; ``camera``: the raster camera; ``world_color``: a ``materials.World`` (its SH
    light) or a constant colour; ``plan``: the frame's ``shadows.ShadowPlan``; ``inputs``:
    the rest (``LitInputs``), the techniques' parts among them: the lit program takes their
    ``ProgramPart`` values, the frame block their rows."""
    if len(lights) > MAX_LIGHTS:
        raise ValueError(f"{len(lights)} lights; the lit pass takes at most {MAX_LIGHTS}")
    rows, samplers, blocks = {}, {}, {}
    for part in inputs.parts:
        rows.update(part.rows)
        samplers.update(part.samplers)
        blocks.update(part.blocks)
    disk = disk_samples(settings, inputs.sample_count)
    order, sampled, shadowed = shading_order(lights, plan)
    sh = getattr(world_color, "sh", None)  # a materials.World, or a constant colour
    atlas, origin = inputs.atlas, (_ZERO if inputs.origin is None else inputs.origin)
    frame = frame_row(
        camera,
        world_color.mean if sh is not None else world_color,
        len(order),
        settings,
        atlas.tile_size,
        atlas.columns,
        origin,
    )
    if sh is not None and inputs.world_sh:
        for k in range(1, 9):
            frame[f"world_sh{k}"] = (*sh[k], 0.0)
    if not inputs.world_sh:
        frame["world_color"] = _ZERO
    frame["alpha_offset"] = inputs.alpha_offset
    frame["sample_index"] = int(inputs.sample_index)
    frame.update(rows)
    frame["shadowed_count"] = shadowed
    frame["shadowed_mask"] = light_bins.word_masks(0, shadowed, LIGHT_WORDS)
    frame["sampled_count"] = sampled
    frame["sampled_mask"] = light_bins.word_masks(0, sampled, LIGHT_WORDS)
    bins = None
    if inputs.rects is not None and should_bin(lights):
        size = inputs.size
        bins = light_bins.bin_masks([inputs.rects[i] for i in order], size[0], size[1], LIGHT_WORDS)
    # A part with an entry shader of its own (the settle test's flags): no debug view's values.
    parts = tuple(p.program for p in inputs.parts if p.program is not None)
    settle = any(p.fragment for p in parts)
    term = 0 if settle else DEBUG_VIEW[getattr(settings, "debug_view", "NONE")].term
    variant = LitVariant(
        **{
            "shadow_filter": settings.shadow_filter if shadowed > sampled else "NONE",  # no map: no filter code at all
            "pcf_weights": _pcf_weights(int(settings.pcf_kernel_size)),
            "specular_model": settings.specular_model,
            "depth_format": atlas.depth_format,
            "disk_samples": int(disk),
            "early_out": bool(settings.shadow_early_out),
            "aux_outputs": bool(inputs.aux_outputs),
            "binned": bins is not None,
            "pcf_spacing": float(settings.pcf_spacing),
            "sampled": sampled > 0,
            "light_counts": (sampled, shadowed, len(order)),
            "light_linking": any(light.receivers is not None for light in lights),
            "debug": bool(_debug_lit(settings)) and not settle,
            "world_lights": bool(inputs.world_sampled) or any(lights[i].world for i in order),
            "debug_term": int(term),
        }
    )
    return FrameData(
        frame=FRAME_STRUCT.pack([frame]),
        lights=LIGHT_STRUCT.pack(
            [kept_light_row(inputs.light_rows, lights[i], plan.lights.get(i), origin) for i in order], MAX_LIGHTS
        ),
        tiles=packed_tiles(plan, origin),
        variant=variant,
        disk_samples=disk if sampled or (shadowed and SHADOW_FILTER[settings.shadow_filter].disk) else 0,
        order=order,
        bins=bins,
        samplers=samplers,
        blocks=blocks,
        begins=tuple(part.begin for part in inputs.parts if part.begin is not None),
        betweens=tuple(part.between for part in inputs.parts if part.between is not None),
        parts=parts,
        blended_parts=tuple(p.blended_program for p in inputs.parts if p.blended_program is not None),
    )


BIN_MIN_LOCAL_LIGHTS = 2


def should_bin(lights):
    """Bin the lights when at least BIN_MIN_LOCAL_LIGHTS of them light only part of space
    (spots, area lights): below that, the per-pixel bin lookup costs more than it saves."""
    return sum(light.type in ("SPOT", "AREA") for light in lights) >= BIN_MIN_LOCAL_LIGHTS
