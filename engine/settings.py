"""Every Penumbra setting, declared once as data. No bpy.

A ``Param`` row (name, type, default, range, description, where it shows) is the one place a
setting is written. From these rows come:
  * the PropertyGroups ``scene.penumbra`` and ``light.penumbra`` (``properties.py``),
  * the plain ``RenderSettings`` the renderer reads (``render_settings`` below),
  * the panels (``ui/panels.py`` draws the rows of each section in order),
  * the post layers' parameters (each effect declares its own rows, ``engine/post``).

Saved files are versioned: ``SCHEMA_VERSION`` is stored with the settings, and ``UPGRADES``
lists, per version, the steps that bring older stored values forward (a renamed setting keeps
its value). ``properties.py`` runs them when a file is loaded.
"""

import dataclasses
from dataclasses import dataclass

from .enums import DEBUG_VIEW, DEPTH_FORMAT, SHADOW_FILTER, SPECULAR_MODEL, SUN_FIT

TYPES = ("FLOAT", "INT", "BOOL", "COLOR", "ENUM", "IMAGE")


@dataclass(frozen=True)
class Param:
    """One setting. ``min``/``max`` are hard limits (the property refuses values outside and
    ``clamp`` applies them to values from any other source); ``soft_*`` only guide sliders."""

    name: str
    type: str  # one of TYPES; IMAGE is an Image datablock or None
    default: object
    description: str = ""
    min: float = None
    max: float = None
    soft_min: float = None
    soft_max: float = None
    step: int = None  # Blender's slider step (for INT: the increment)
    subtype: str = "NONE"
    enum: object = None  # ENUM: the owning enums.Enum
    label: str = None
    section: str = None  # panel section it is drawn in; None: not drawn by the generic panels
    active_when: tuple = None  # (other param, fact): greyed out unless enum[other].fact is true
    unit: str = None  # "PIXELS": a size in output pixels, scaled with the resolution %
    precision: int = None  # FLOAT: digits a field shows (Blender's default 3 otherwise)
    switch: str = None  # a BOOL setting drawn as this row's checkbox (Cycles' "Noise Threshold" row)

    def __post_init__(self):
        if self.type not in TYPES:
            raise ValueError(f"{self.name}: unknown parameter type {self.type!r}")
        if self.type == "ENUM":
            if self.enum is None:
                raise ValueError(f"{self.name}: an ENUM parameter needs its enum")
            self.enum[self.default]  # noqa: B018  (validates the default id)

    @property
    def ui_label(self):
        return self.label or self.name.replace("_", " ").title()

    @property
    def items(self):
        """EnumProperty items of an ENUM parameter."""
        return self.enum.blender_items() if self.enum is not None else ()

    @property
    def slider_max(self):
        """The largest value a user is expected to dial in (hard max, else soft max)."""
        return self.max if self.max is not None else self.soft_max

    def clamp(self, value):
        """``value`` as the renderer may use it: numbers within [min, max], enum ids
        validated (an unknown id raises ValueError), colours as tuples."""
        if self.type == "FLOAT":
            v = float(value)
            if self.min is not None:
                v = max(v, float(self.min))
            if self.max is not None:
                v = min(v, float(self.max))
            return v
        if self.type == "INT":
            v = int(value)
            if self.min is not None:
                v = max(v, int(self.min))
            if self.max is not None:
                v = min(v, int(self.max))
            return v
        if self.type == "BOOL":
            return bool(value)
        if self.type == "COLOR":
            return tuple(float(c) for c in value)
        if self.type == "ENUM":
            return self.enum[value].id
        return value  # IMAGE

    def is_active(self, group, params):
        """Whether a panel shows this row as active, given the values of ``group`` (whose
        declarations are ``params``)."""
        if self.active_when is None:
            return True
        other, fact = self.active_when
        enum = next(p.enum for p in params if p.name == other)
        return bool(getattr(enum[getattr(group, other)], fact))


def scale_pixels(params, namespace, scale):
    """Sizes in pixels (``unit="PIXELS"``) of a values namespace scaled by ``scale`` (the
    resolution %), so a preview at 25 % looks like the full frame; whole-pixel sizes are
    rounded and kept within their limits."""
    if scale == 1.0:
        return namespace
    for p in params:
        if p.unit == "PIXELS":
            v = getattr(namespace, p.name) * scale
            setattr(namespace, p.name, p.clamp(round(v) if p.type == "INT" else v))
    return namespace


def values(params, source):
    """{name: clamped value} of ``params`` read from ``source`` (a PropertyGroup or any
    object with those attributes)."""
    return {p.name: p.clamp(getattr(source, p.name)) for p in params}


# --- scene settings (scene.penumbra) ------------------------------------------------------

SAMPLING = "sampling"
SAMPLING_VIEWPORT = "sampling_viewport"  # the Sampling panel's Viewport and Render subpanels (as Cycles')
SAMPLING_RENDER = "sampling_render"
SHADOWS = "shadows"
LIGHTING = "lighting"
WORLD = "world"  # World Properties › Penumbra (the world's light and its visibility)
LIGHT_PATHS = "light_paths"  # Render Properties › Light Paths (indirect light)
VOLUMES = "volumes"  # Render Properties › Volumes (participating media)
VIEWPORT = "viewport"
SIMPLIFY = "simplify"
DEBUG = "debug"

SCENE_PARAMS = (
    Param(
        "use_preview_adaptive_sampling",
        "BOOL",
        True,
        "Automatically reduce the number of samples per pixel based on estimated noise level, for viewport renders",
        label="Use Adaptive Sampling",
        section=SAMPLING_VIEWPORT,
    ),
    Param(
        "preview_adaptive_threshold",
        "FLOAT",
        0.1,
        "Noise level step to stop sampling at, lower values reduce noise at the cost of render time, for viewport "
        "renders. Zero turns adaptive sampling off (every pixel takes every sample)",
        min=0.0,
        max=1.0,
        soft_min=0.001,
        precision=4,
        label="Noise Threshold",
        section=SAMPLING_VIEWPORT,
        switch="use_preview_adaptive_sampling",
    ),
    Param(
        "viewport_samples",
        "INT",
        16,
        "Samples the viewport accumulates while nothing changes (0: keep refining)",
        min=0,
        max=4096,
        soft_max=256,
        label="Max Samples",
        section=SAMPLING_VIEWPORT,
    ),
    Param(
        "preview_adaptive_min_samples",
        "INT",
        0,
        "Minimum AA samples for adaptive sampling, to discover noisy features before stopping sampling. Zero for "
        "automatic setting based on noise threshold, for viewport renders",
        min=0,
        max=4096,
        label="Min Samples",
        section=SAMPLING_VIEWPORT,
    ),
    Param(
        "preview_time_limit",
        "FLOAT",
        0.0,
        "Limit the time the viewport keeps refining a still view, in seconds (excluding synchronization time). "
        "Zero disables the limit",
        min=0.0,
        step=100,
        subtype="TIME_ABSOLUTE",
        label="Time Limit",
        section=SAMPLING_VIEWPORT,
    ),
    Param(
        "use_adaptive_sampling",
        "BOOL",
        True,
        "Automatically reduce the number of samples per pixel based on estimated noise level",
        label="Use Adaptive Sampling",
        section=SAMPLING_RENDER,
    ),
    Param(
        "adaptive_threshold",
        "FLOAT",
        0.01,
        "Noise level step to stop sampling at, lower values reduce noise at the cost of render time. Zero turns "
        "adaptive sampling off (every pixel takes every sample)",
        min=0.0,
        max=1.0,
        soft_min=0.001,
        precision=4,
        label="Noise Threshold",
        section=SAMPLING_RENDER,
        switch="use_adaptive_sampling",
    ),
    Param(
        "render_samples",
        "INT",
        16,
        "Samples per pixel of a final render: each one jitters the image within the pixel filter and "
        "lights soft lights from another point of themselves",
        min=1,
        max=4096,
        soft_max=256,
        label="Max Samples",
        section=SAMPLING_RENDER,
    ),
    Param(
        "adaptive_min_samples",
        "INT",
        0,
        "Minimum AA samples for adaptive sampling, to discover noisy features before stopping sampling. Zero for "
        "automatic setting based on noise threshold",
        min=0,
        max=4096,
        label="Min Samples",
        section=SAMPLING_RENDER,
    ),
    Param(
        "time_limit",
        "FLOAT",
        0.0,
        "Limit the render time (excluding synchronization time). Zero disables the limit",
        min=0.0,
        step=100,
        subtype="TIME_ABSOLUTE",
        label="Time Limit",
        section=SAMPLING_RENDER,
    ),
    Param(
        "filter_size",
        "FLOAT",
        1.5,
        "How far the pixel filter (Blackman-Harris) the samples are spread over reaches each way, in pixels: "
        "the same image as Cycles' Pixel Filter Width and EEVEE's Filter Size of this value",
        min=0.0,
        max=10.0,
        label="Filter Size",
        section=SAMPLING,
        subtype="PIXEL",
    ),
    Param(
        "shadow_map_jitter",
        "BOOL",
        True,
        "With several samples, shift every shadow map by a different fraction of a texel in each "
        "sample (and light every sun, point and spot light from points of its disc or sphere, "
        "however small): edges then converge to where the geometry puts them instead of keeping "
        "one map's stair steps and offsets. Shadowed lights redraw their maps every sample",
        label="Jitter Shadow Maps",
        section=SAMPLING,
    ),
    Param("shadow_filter", "ENUM", "PCF", "How shadow edges are filtered", enum=SHADOW_FILTER, section=SHADOWS),
    Param(
        "shadow_map_size",
        "INT",
        2048,
        "Texels per side of each shadow map (clamped to the GPU's maximum)",
        min=1,
        soft_max=8192,
        section=SHADOWS,
    ),
    Param(
        "shadow_texels_per_pixel",
        "FLOAT",
        4.0,
        "Each map gets the fewest texels (a power of two, at most the Shadow Map Size) that still "
        "give every pixel it shadows this many texels across, times the radius of the PCF or "
        "jittered-disk kernel: pixels that cannot show more detail cost no more fill. 0: every map "
        "has the full size",
        min=0.0,
        soft_max=8.0,
        label="Texels per Pixel",
        section=SHADOWS,
    ),
    Param("shadow_depth_format", "ENUM", "FLOAT32", "How shadow depth is stored", enum=DEPTH_FORMAT, section=SHADOWS),
    Param(
        "shadow_sun_fit",
        "ENUM",
        "VIEW",
        "What a sun's shadow map covers",
        enum=SUN_FIT,
        label="Sun Fit",
        section=SHADOWS,
    ),
    Param(
        "shadow_cascades",
        "INT",
        0,
        "Shadow maps a sun splits the visible depth range into (View fit): 0 chooses 1 to 4 from the ratio "
        "of the farthest to the nearest visible depth",
        min=0,
        max=4,
        label="Sun Cascades",
        section=SHADOWS,
    ),
    Param(
        "pcf_kernel_size",
        "INT",
        5,
        "Width N of the NxN PCF kernel (made odd)",
        min=1,
        max=15,
        label="PCF Kernel",
        section=SHADOWS,
        active_when=("shadow_filter", "pcf_taps"),
    ),
    Param(
        "pcf_spacing",
        "FLOAT",
        1.0,
        "Distance between PCF taps, in texels",
        min=0.0,
        soft_max=8.0,
        label="PCF Spacing",
        section=SHADOWS,
        active_when=("shadow_filter", "pcf_taps"),
    ),
    Param(
        "shadow_samples",
        "INT",
        16,
        "Samples of the jittered-disk and PCSS filters (rounded down to a multiple of 8)",
        min=8,
        max=64,
        step=8,
        section=SHADOWS,
        active_when=("shadow_filter", "disk"),
    ),
    Param(
        "shadow_filter_radius",
        "FLOAT",
        2.0,
        "Radius of the jittered-disk filter, in shadow-map texels",
        min=0.0,
        max=32.0,
        soft_max=16.0,
        label="Filter Radius",
        section=SHADOWS,
        active_when=("shadow_filter", "fixed_radius"),
    ),
    Param(
        "shadow_early_out",
        "BOOL",
        True,
        "Disk filters: skip the inner samples where the outer ring agrees",
        label="Early Out",
        section=SHADOWS,
        active_when=("shadow_filter", "early_out"),
    ),
    Param(
        "shadow_caster_detail",
        "FLOAT",
        2.0,
        "Draw detailed casters into each shadow map with their triangles merged on a grid of this "
        "many map texels (at the caster's nearest point to the light; every vertex stays in its "
        "cell), so a map costs what it can resolve. The image keeps every triangle. 0: every "
        "triangle in every map",
        min=0.0,
        soft_max=4.0,
        label="Caster Detail",
        section=SHADOWS,
    ),
    Param(
        "shadow_bias",
        "FLOAT",
        0.5,
        "Depth bias in shadow-map texels",
        min=0.0,
        soft_max=10.0,
        label="Constant Bias",
        section=SHADOWS,
    ),
    Param(
        "shadow_slope_bias",
        "FLOAT",
        1.0,
        "Extra depth bias in texels per unit of tan(angle to the light)",
        min=0.0,
        soft_max=10.0,
        label="Slope Bias",
        section=SHADOWS,
    ),
    Param(
        "shadow_normal_offset",
        "FLOAT",
        1.0,
        "Offset of the lookup along the surface normal, in texels",
        min=0.0,
        soft_max=10.0,
        label="Normal Offset",
        section=SHADOWS,
    ),
    Param(
        "shadow_receiver_plane",
        "BOOL",
        True,
        "Compare each filter tap with the receiver's own plane at that texel (its facet's slope "
        "towards the light) instead of a slope bias that grows with the filter's width: fine "
        "geometry keeps its self-shadowing and contact shadows under wide filters",
        label="Receiver Plane",
        section=SHADOWS,
    ),
    Param(
        "shadow_cull_front",
        "BOOL",
        False,
        "Draw only back faces into shadow maps (less acne on closed meshes)",
        label="Cull Front Faces",
        section=SHADOWS,
    ),
    Param(
        "specular_model",
        "ENUM",
        "GGX",
        "Shape of the specular highlight",
        enum=SPECULAR_MODEL,
        label="Specular",
        section=LIGHTING,
    ),
    Param(
        "world_shadows",
        "BOOL",
        True,
        "The world's light is blocked by what stands in its way: each sample draws a shadow map for a few "
        "directions taken from the world's light, so the frame converges to Cycles' direct light from the "
        "world. Off: the world lights every surface as if nothing stood in its way",
        label="Shadows",
        section=WORLD,
    ),
    Param(
        "world_samples",
        "INT",
        4,
        "Directions of the world's light per sample at most, each with its own shadow map (importance-sampled "
        "from the world's light, stratified over the frame's samples); a world that gives under half the light "
        "reaching the view takes fewer, in proportion, one at least",
        min=1,
        max=16,
        label="Directions per Sample",
        section=WORLD,
    ),
    Param(
        "world_map_size",
        "INT",
        512,
        "Texels per side of each world direction's shadow map (at most the Shadow Map Size)",
        min=16,
        soft_max=4096,
        label="Map Size",
        section=WORLD,
    ),
    Param(
        "world_ao",
        "BOOL",
        True,
        "One-sample frames (the viewport while the view moves) and a frame's first sample estimate the "
        "world's visibility from the depth buffer (ground-truth ambient occlusion); later samples use the "
        "world's shadow maps",
        label="Ambient Occlusion",
        section=WORLD,
    ),
    Param(
        "world_ao_distance",
        "FLOAT",
        0.0,
        "How far the ambient occlusion looks for what blocks the world's light (0: automatic, a tenth of the "
        "size of everything drawn, so it does the same in a scene of millimetres or of kilometres)",
        min=0.0,
        soft_max=100.0,
        subtype="DISTANCE",
        label="Distance",
        section=WORLD,
    ),
    Param(
        "indirect_bounces",
        "INT",
        0,
        "Diffuse bounces of light from suns, spots and area lights (and the world with Shadows on): 1 adds "
        "the light their shadow maps see reflected once (reflective shadow maps), sampled anew each sample",
        min=0,
        max=1,
        label="Diffuse Bounces",
        section=LIGHT_PATHS,
    ),
    Param(
        "indirect_samples",
        "INT",
        16,
        "Points of each light's reflective shadow map gathered per pixel and sample; the world's directions "
        "share them, as one light",
        min=1,
        max=256,
        label="Bounce Samples",
        section=LIGHT_PATHS,
    ),
    Param(
        "volume_samples",
        "INT",
        64,
        "Steps of each pixel's march through the media it crosses (EEVEE's Volumes > Samples), spread over "
        "the frame's samples (8 a sample at least); each sample places its steps anew, so the frame's samples "
        "converge to the media's single scattering",
        min=1,
        max=256,
        label="Steps",
        section=VOLUMES,
    ),
    Param(
        "screen_space_reflections",
        "BOOL",
        True,
        "Glossy surfaces sharper than roughness 0.5 reflect the scene the camera sees: every sample after a "
        "frame's first traces one ray per pixel in screen space and reads the image the samples so far made "
        "where it meets a surface. Where the ray meets nothing on the screen, and in one-sample frames (the "
        "viewport while the view moves), the surface reflects the world. Off: glossy surfaces reflect the "
        "world alone",
        label="Screen Space Reflections",
        section=LIGHT_PATHS,
    ),
    Param(
        "navigation_scale",
        "FLOAT",
        0.5,
        "Resolution scale of the viewport while the view moves; once it stops, the viewport renders "
        "at full resolution (1: always full resolution)",
        min=0.1,
        max=1.0,
        label="Navigation Scale",
        section=VIEWPORT,
        subtype="FACTOR",
    ),
    Param(
        "simplify_pixels",
        "FLOAT",
        2.0,
        "While Simplify is on, merge each mesh's triangles into cells this many pixels wide, "
        "judged at the instance's point nearest the camera (pixels of the full-resolution frame): "
        "fewer triangles where the frame cannot show them apart. A surface moves by a small part "
        "of a cell, never more than its diagonal. Meshes whose materials read UVs, colour "
        "attributes or tangents, or use alpha, are drawn whole. 0: every triangle is drawn",
        min=0.0,
        soft_max=8.0,
        label="Merge Below",
        section=SIMPLIFY,
        unit="PIXELS",
    ),
    Param(
        "debug_view",
        "ENUM",
        "NONE",
        "Show what a frame's quality and time went to instead of the image, in the viewport and the final "
        "render: the shadow maps, texel density, sun cascades, lights per pixel, samples per pixel or the "
        "noise estimate adaptive sampling uses",
        enum=DEBUG_VIEW,
        label="Debug View",
        section=DEBUG,
    ),
)

# --- light settings (light.penumbra) ------------------------------------------------------

LIGHT_PARAMS = (
    Param(
        "bias_scale",
        "FLOAT",
        1.0,
        "Multiplies the scene's shadow biases for this light",
        min=0.0,
        soft_max=10.0,
        section=SHADOWS,
    ),
)


# --- view layer settings (view_layer.penumbra) -----------------------------------------------

PASSES = "passes"

VIEW_LAYER_PARAMS = (
    Param(
        "use_pass_shadow",
        "BOOL",
        False,
        "Shadow pass: the fraction of direct light that arrives (1 = unshadowed, luminance-weighted over lights)",
        label="Shadow",
        section=PASSES,
    ),
    Param(
        "use_pass_lit",
        "BOOL",
        False,
        "Lit pass: Combined before the post stack, so it lines up with Depth and Shadow whatever the layers do",
        label="Lit (Before Post)",
        section=PASSES,
    ),
    Param(
        "use_pass_denoising",
        "BOOL",
        False,
        "Denoising Albedo and Denoising Normal passes, averaged over the samples: the Albedo and Normal inputs "
        "of the compositor's Denoise node",
        label="Denoising Data",
        section=PASSES,
    ),
)

# --- what the renderer reads --------------------------------------------------------------

RenderSettings = dataclasses.make_dataclass(
    "RenderSettings",
    [(p.name, object, dataclasses.field(default=p.default)) for p in SCENE_PARAMS]
    + [
        ("film_transparent", bool, dataclasses.field(default=False)),
        ("use_simplify", bool, dataclasses.field(default=False)),  # Render › Simplify's switch
        ("pixel_scale", float, dataclasses.field(default=1.0)),  # resolution % / 100 of a final render
        ("frame", int, dataclasses.field(default=1)),
        ("layers", list, dataclasses.field(default_factory=list)),  # [post.Layer] in stack order
    ],
    namespace={"__doc__": "Everything a frame needs from the scene, as plain validated values."},
)
RenderSettings.__module__ = __name__


def render_settings(source, **extra):
    """RenderSettings from ``source`` (``scene.penumbra`` or any object carrying the scene
    settings), validated and clamped; ``extra`` sets the non-declared fields (frame, layers,
    film_transparent)."""
    return RenderSettings(**values(SCENE_PARAMS, source), **extra)


# --- versioning of saved settings ---------------------------------------------------------

SCHEMA_VERSION = 1


@dataclass(frozen=True)
class Rename:
    """A stored setting renamed from ``old`` to ``new``. ``path`` reaches nested groups
    (``("layers", "*", "blur")``: the blur group of every layer)."""

    old: str
    new: str
    path: tuple = ()

    def apply(self, stored):
        changed = 0
        for group in _groups_at(stored, self.path):
            if self.old in group and self.new not in group:
                group[self.new] = group[self.old]
                del group[self.old]
                changed += 1
        return changed


@dataclass(frozen=True)
class Renumber:
    """An enum setting whose stored numbers changed: ``{old number: new number}``."""

    name: str
    mapping: tuple  # ((old, new), ...)
    path: tuple = ()

    def apply(self, stored):
        changed = 0
        table = dict(self.mapping)
        for group in _groups_at(stored, self.path):
            if self.name in group and group[self.name] in table:
                group[self.name] = table[group[self.name]]
                changed += 1
        return changed


def _groups_at(stored, path):
    groups = [stored]
    for key in path:
        nxt = []
        for g in groups:
            if key == "*":
                nxt.extend(g)
            elif key in g:
                nxt.append(g[key])
        groups = nxt
    return groups


# Version -> steps that bring version - 1 to it. Version 1 is the first versioned layout.
SCENE_UPGRADES = {1: ()}
LIGHT_UPGRADES = {1: ()}


def upgrade(stored, upgrades, current=SCHEMA_VERSION, key="schema_version"):
    """Bring the stored settings ``stored`` (a mapping: a Blender IDPropertyGroup or a dict)
    from their saved version to ``current``. Settings saved before versioning existed count
    as version 0. Returns (saved version, changes made); a file from a newer version is left
    alone (its version is returned, so the caller can warn)."""
    saved = int(stored.get(key, 0))
    changes = 0
    if saved > current:
        return saved, 0
    for version in range(saved + 1, current + 1):
        for step in upgrades.get(version, ()):
            changes += step.apply(stored)
    stored[key] = current
    return saved, changes
