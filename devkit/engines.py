"""The one place that sets a scene up for an engine, so every benchmark and test compares the
same engines in the same way:

Penumbra   ``scene.penumbra`` as it is, plus the settings passed in.
EEVEE      ``BLENDER_EEVEE_NEXT`` (4.x) or ``BLENDER_EEVEE`` (5.x): 16 TAA render samples,
           shadows on, everything else at factory defaults.
Workbench  factory defaults.
Cycles     CPU, 16 samples unless given, no adaptive sampling, no denoiser, a fixed seed;
           direct light only (no bounces, no caustics), which is the light Penumbra computes;
           a near-point box pixel filter, so every sample lands near the pixel centre, where
           the rasterisers sample. This makes Cycles a shadow reference and a like-for-like
           speed comparison at once.
"""

import bpy

EEVEE_SAMPLES = 16
CYCLES_SAMPLES = 16

# Keys of configure() and what each one is called in tables.
LABELS = {"PENUMBRA": "Penumbra", "EEVEE": "EEVEE", "WORKBENCH": "Workbench", "CYCLES": "Cycles"}

SUMMARY = (
    f"EEVEE: {EEVEE_SAMPLES} TAA render samples, shadows on. Cycles: CPU, direct light only, no adaptive "
    f"sampling, no denoiser, box pixel filter ({CYCLES_SAMPLES} samples unless stated). Workbench: defaults."
)


def eevee_id():
    """EEVEE's engine id on this Blender: 'BLENDER_EEVEE_NEXT' (4.2-4.5) or 'BLENDER_EEVEE' (5.x)."""
    items = {item.identifier for item in bpy.types.RenderSettings.bl_rna.properties["engine"].enum_items}
    for candidate in ("BLENDER_EEVEE_NEXT", "BLENDER_EEVEE"):
        if candidate in items:
            return candidate
    raise RuntimeError(f"no EEVEE engine among {sorted(items)}")


def _penumbra(scene):
    scene.render.engine = "PENUMBRA"
    return scene.penumbra


def _eevee(scene):
    scene.render.engine = eevee_id()
    scene.eevee.taa_render_samples = EEVEE_SAMPLES
    scene.eevee.use_shadows = True
    return scene.eevee


def _workbench(scene):
    scene.render.engine = "BLENDER_WORKBENCH"
    return scene.display.shading


def _cycles(scene):
    scene.render.engine = "CYCLES"
    c = scene.cycles
    c.device = "CPU"
    c.samples = CYCLES_SAMPLES
    c.use_adaptive_sampling = False  # a fixed amount of work per pixel
    c.use_denoising = False
    c.seed = 0
    c.use_animated_seed = False
    c.max_bounces = 0  # direct light only: camera ray -> surface -> light
    for bounces in (
        "diffuse_bounces",
        "glossy_bounces",
        "transmission_bounces",
        "volume_bounces",
        "transparent_max_bounces",
    ):
        setattr(c, bounces, 0)
    c.caustics_reflective = c.caustics_refractive = False
    c.pixel_filter_type = "BOX"
    c.filter_width = 0.01
    return c


_SETUP = {"PENUMBRA": _penumbra, "EEVEE": _eevee, "WORKBENCH": _workbench, "CYCLES": _cycles}
_ALIASES = {"BLENDER_EEVEE": "EEVEE", "BLENDER_EEVEE_NEXT": "EEVEE", "BLENDER_WORKBENCH": "WORKBENCH"}


def configure(scene, engine, **settings):
    """Set ``scene`` up for ``engine`` ('PENUMBRA', 'EEVEE', 'WORKBENCH' or 'CYCLES'; Blender's
    own ids work too) as described above, then apply ``settings``: attributes of that engine's
    settings (``scene.penumbra``, ``scene.eevee``, ``scene.display.shading``, ``scene.cycles``),
    e.g. ``shadow_filter='PCSS'`` or ``samples=64``. Returns the scene."""
    key = engine.upper()
    key = _ALIASES.get(key, key)
    if key not in _SETUP:
        raise ValueError(f"unknown engine {engine!r}; known: {', '.join(_SETUP)}")
    group = _SETUP[key](scene)
    for name, value in settings.items():
        if not hasattr(group, name):
            raise AttributeError(f"{key}: no setting {name!r}")
        setattr(group, name, value)
    return scene
