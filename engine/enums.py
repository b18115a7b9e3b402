"""Every enum of Penumbra, each with one owner: id, label, description, the number stored in
.blend files and used in GLSL, and the facts other code asks about ("uses PCF taps").

No bpy, no gpu. Properties, shader defines, panels and tests all read these objects, so an id
is typed once. Looking up an unknown id raises ``ValueError``: nothing falls back silently.

Numbers are explicit and never reused: Blender stores an EnumProperty as its number, so
items can be reordered or relabelled without changing what a saved file means.
"""

from dataclasses import dataclass, field
from types import MappingProxyType


@dataclass(frozen=True)
class Item:
    id: str
    label: str
    description: str
    value: int  # stored in .blend files and compared in GLSL
    icon: str = "NONE"
    facts: MappingProxyType = field(default_factory=lambda: MappingProxyType({}))

    def __getattr__(self, name):
        # Facts read as attributes: SHADOW_FILTER["PCF"].pcf_taps. Unknown facts are errors.
        facts = object.__getattribute__(self, "facts")
        if name in facts:
            return facts[name]
        raise AttributeError(f"{self.id} has no fact {name!r}")


class Enum:
    """An ordered set of items. ``prefix`` names the GLSL defines (``FILTER_PCF``)."""

    def __init__(self, name, prefix, items, fact_defaults=None):
        self.name = name
        self.prefix = prefix
        defaults = dict(fact_defaults or {})
        built = []
        for row in items:
            ident, label, description, value, *rest = row
            icon = rest[0] if rest and isinstance(rest[0], str) else "NONE"
            facts = {**defaults, **(rest[-1] if rest and isinstance(rest[-1], dict) else {})}
            unknown = set(facts) - set(defaults)
            if unknown:
                raise ValueError(f"{name}: {ident} declares undeclared facts {sorted(unknown)}")
            built.append(Item(ident, label, description, int(value), icon, MappingProxyType(facts)))
        self.items = tuple(built)
        self._by_id = {item.id: item for item in self.items}
        if len(self._by_id) != len(self.items):
            raise ValueError(f"{name}: duplicate ids")
        if len({item.value for item in self.items}) != len(self.items):
            raise ValueError(f"{name}: duplicate numbers")

    def __getitem__(self, ident):
        try:
            return self._by_id[ident]
        except (KeyError, TypeError):
            raise ValueError(f"unknown {self.name} {ident!r}; expected one of {', '.join(self.ids)}") from None

    def __contains__(self, ident):
        return ident in self._by_id

    def __iter__(self):
        return iter(self.items)

    def __len__(self):
        return len(self.items)

    @property
    def ids(self):
        return tuple(item.id for item in self.items)

    def value(self, ident):
        return self[ident].value

    def with_fact(self, fact):
        """Ids of the items whose ``fact`` is true."""
        return frozenset(item.id for item in self.items if item.facts[fact])

    def define(self, ident):
        """The GLSL name of ``ident`` (``FILTER_PCF``), validated."""
        return f"{self.prefix}_{self[ident].id}"

    def defines(self):
        """{``PREFIX_ID``: number} for every item, for shader sources."""
        return {f"{self.prefix}_{item.id}": item.value for item in self.items}

    def blender_items(self):
        """EnumProperty items ``(id, label, description, icon, number)``."""
        return tuple((i.id, i.label, i.description, i.icon, i.value) for i in self.items)


SHADOW_FILTER = Enum(
    "shadow filter",
    "FILTER",
    (
        ("NONE", "None", "One depth comparison per pixel: hard, aliased edges", 0),
        ("HARDWARE", "Hardware 2x2", "Bilinear-weighted 2x2 comparison, as a filtering compare sampler gives", 1),
        ("PCF", "PCF", "Percentage-closer filtering with an NxN Gaussian-weighted kernel", 2, {"pcf_taps": True}),
        (
            "JITTER",
            "Jittered Disk",
            "Disk samples jittered per pixel, with an early out where the outer ring agrees",
            3,
            {"disk": True, "fixed_radius": True, "early_out": True},
        ),
        (
            "PCSS",
            "PCSS",
            "Contact-hardening soft shadows: penumbra width from the light's size and the blocker distance",
            4,
            {"disk": True, "early_out": True},
        ),
    ),
    # pcf_taps: reads the NxN kernel; disk: reads the jittered disk (shadow_samples);
    # fixed_radius: its width is shadow_filter_radius; early_out: honours shadow_early_out.
    fact_defaults={"pcf_taps": False, "disk": False, "fixed_radius": False, "early_out": False},
)

DEPTH_FORMAT = Enum(
    "depth format",
    "DEPTH",
    (
        (
            "FLOAT32",
            "Float 32",
            "32-bit float depth",
            0,
            {"texture": "DEPTH_COMPONENT32F", "bytes": 4, "depth_only": True, "channels": 1},
        ),
        (
            "FLOAT16",
            "Float 16",
            "16-bit float depth: half the memory, less precision",
            1,
            {"texture": "R16F", "bytes": 2, "channels": 1},
        ),
        (
            "RGBA8",
            "RGBA8 Packed",
            "Depth packed into four 8-bit channels (the classic encoding)",
            2,
            {"texture": "RGBA8", "bytes": 4, "channels": 4},
        ),
    ),
    # depth_only: the map is the depth buffer itself (no colour target, no copy).
    # channels: texture channels one depth value spans.
    fact_defaults={"texture": None, "bytes": 0, "depth_only": False, "channels": 1},
)

SPECULAR_MODEL = Enum(
    "specular model",
    "SPECULAR",
    (
        ("BLINN", "Blinn-Phong", "Normalised Blinn-Phong highlight (half vector)", 0),
        ("PHONG", "Phong", "Normalised Phong highlight (reflection vector)", 1),
        ("GGX", "GGX", "GGX microfacet highlight with Smith shadowing and Fresnel, as the Principled BSDF", 2),
    ),
)

SUN_FIT = Enum(
    "sun fit",
    "SUN_FIT",
    (
        ("VIEW", "View", "Fit sun maps to what the camera sees: sharpest, redrawn when the view changes the fit", 0),
        (
            "SCENE",
            "Scene",
            "Fit sun maps to the whole scene: never redrawn for camera moves, coarser in large scenes",
            1,
        ),
    ),
)

LIGHT_TYPE = Enum(
    "light type",
    "LIGHT",
    (
        ("SUN", "Sun", "Directional light", 0),
        ("POINT", "Point", "Omnidirectional point light", 1),
        ("SPOT", "Spot", "Cone light", 2),
        ("AREA", "Area", "Emitting surface (shaded as a far-field point)", 3),
    ),
)

SHADOW_MODE = Enum(
    "shadow mode",
    "SHADOW_MODE",
    (
        ("NONE", "None", "No shadow map", -1),
        ("SINGLE", "Single", "One map (sun, spot)", 0),
        ("CUBE", "Cube", "Up to six cube faces (point, area)", 1),
        ("CASCADE", "Cascade", "Up to four maps over slices of the visible depth range (sun)", 2),
    ),
)

DEBUG_VIEW = Enum(
    "debug view",
    "DEBUG_VIEW",
    (
        ("NONE", "None", "The rendered image", 0),
        (
            "SHADOW_MAPS",
            "Shadow Maps",
            "The shadow atlas as drawn this frame (near dark, far light), each map outlined and labelled with its "
            "light, cube face or cascade and size in texels",
            1,
            {"legend": "shadow atlas depth: near dark, far light; outlines: each map, labelled light/face/size"},
        ),
        (
            "TEXEL_DENSITY",
            "Texel Density",
            "Shadow-map texels per screen pixel at each shaded point, of the worst-sampled light there: red "
            "undersampled, green matched, blue wasted",
            2,
            {
                "lit": True,
                "legend": "texels per pixel (worst light): red < 1 undersampled, green 1 matched, blue > 1 wasted; "
                "grey: no map",
            },
        ),
        (
            "CASCADES",
            "Cascades",
            "Which cascade of a sun's map shades each pixel",
            3,
            {"lit": True, "legend": "sun cascade: red 0, green 1, blue 2, yellow 3; grey: no cascaded sun"},
        ),
        (
            "LIGHT_COST",
            "Light Cost",
            "Lights evaluated per pixel (the screen bins' lists)",
            4,
            {"lit": True, "legend": "lights evaluated per pixel: dark 0 to bright at the frame's most"},
        ),
        (
            "SAMPLES",
            "Samples",
            "Samples taken per pixel (adaptive sampling stops converged pixels early)",
            5,
            {"legend": "samples per pixel: dark 1 to bright at the frame's samples"},
        ),
        (
            "NOISE",
            "Noise",
            "The per-pixel error estimate adaptive sampling compares with the Noise Threshold",
            6,
            {"legend": "noise estimate: green below the Noise Threshold (converged), yellow to red up to 10x it"},
        ),
        (
            "WORLD_AO",
            "World Occlusion",
            "The world's cosine-weighted visibility the ambient occlusion gives each shaded point (World > "
            "Ambient Occlusion), averaged over the frame's samples",
            7,
            {
                "lit": True,
                "legend": "world visibility: black occluded, white open; white everywhere when no occlusion ran "
                "(ambient occlusion off or a black world)",
            },
        ),
        (
            "REFLECTIONS",
            "Reflections",
            "Where the glossy surfaces' screen-space rays met the scene (Light Paths > Screen Space Reflections), "
            "averaged over the frame's samples: every sample traces in this view, the first too",
            10,
            {
                "lit": True,
                "legend": "share of the samples whose reflection ray met the scene: black none (the world is "
                "reflected there, or nothing is traced), white every one",
            },
        ),
        (
            "WORLD_LIGHT",
            "World Light",
            "The light the world alone gives each pixel, with its visibility (its sampled shadow maps, the "
            "ambient occlusion of a frame's first sample), averaged over the frame's samples",
            8,
            {
                "lit": True,
                "term": 1,
                "legend": "the world's light alone, with its visibility, in the render's colours",
            },
        ),
        (
            "INDIRECT",
            "Indirect Light",
            "The light of the one diffuse bounce alone (Light Paths > Diffuse Bounces 1), averaged over the "
            "frame's samples",
            9,
            {
                "lit": True,
                "term": 2,
                "legend": "the diffuse bounce alone, in the render's colours; black with Diffuse Bounces 0",
            },
        ),
        (
            "VOLUME_LIGHT",
            "Volume Light",
            "The light the media scatter and emit towards the camera alone (World > Volume, meshes' Volume "
            "materials), averaged over the frame's samples",
            11,
            {
                "lit": True,
                "term": 3,
                "legend": "the media's in-scattered and emitted light alone, in the render's colours; black "
                "without media",
            },
        ),
        (
            "COAT_LIGHT",
            "Coat Light",
            "What the Principled BSDF's coats reflect alone, of the lights and the world, averaged over the "
            "frame's samples",
            12,
            {
                "lit": True,
                "term": 4,
                "legend": "the coats' reflection alone, in the render's colours; black without a coat",
            },
        ),
        (
            "SHEEN_LIGHT",
            "Sheen Light",
            "The light of the sheens alone (Principled Sheen, Sheen BSDF), under any coat, averaged over the "
            "frame's samples",
            13,
            {
                "lit": True,
                "term": 5,
                "legend": "the sheens' light alone, in the render's colours; black without a sheen",
            },
        ),
        (
            "SUBSURFACE_LIGHT",
            "Subsurface Light",
            "The light scattered below surfaces alone (Principled Subsurface, Subsurface Scattering), spread "
            "as it is drawn, averaged over the frame's samples",
            14,
            {
                "lit": True,
                "term": 6,
                "legend": "the subsurface light alone, in the render's colours; black without a subsurface",
            },
        ),
    ),
    # lit: the lit pass writes the view's values instead of colour (the DEBUG_LIT variant);
    # term: instead, the lit pass writes one term of its colour alone (DEBUG_TERM: 1 the world's
    # light, 2 the diffuse bounce, 3 none: the volumes' march adds its light alone, 4 the coats'
    # reflection, 5 the sheens' light, 6 none: the subsurface diffusion adds its light alone);
    # legend: what
    # the colours mean (the viewport's text and the render report).
    fact_defaults={"lit": False, "term": 0, "legend": ""},
)
