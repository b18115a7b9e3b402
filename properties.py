"""Penumbra's settings: ``scene.penumbra`` and its post-layer collection.

Each layer carries one PointerProperty per effect (``layer.blur.radius``,
``layer.vignette.color``, ...) generated from the effects' parameter declarations, so the
properties, the UI and the presets cannot drift from what the shaders read.
"""

from types import SimpleNamespace

import bpy
from bpy.props import (
    BoolProperty,
    CollectionProperty,
    EnumProperty,
    FloatProperty,
    FloatVectorProperty,
    IntProperty,
    PointerProperty,
    StringProperty,
)

from .engine.post import EFFECTS
from .engine.renderer import RenderSettings

SHADOW_FILTER_ITEMS = (
    ("NONE", "None", "One depth comparison per pixel: hard, aliased edges"),
    ("HARDWARE", "Hardware 2x2", "Bilinear-weighted 2x2 comparison, as a filtering compare sampler gives"),
    ("PCF", "PCF", "Percentage-closer filtering with an NxN Gaussian-weighted kernel"),
    ("JITTER", "Jittered Disk", "Disk samples jittered per pixel, with an early out where the outer ring agrees"),
    ("PCSS", "PCSS", "Contact-hardening soft shadows: penumbra width from the light's size and the blocker distance"),
)

DEPTH_FORMAT_ITEMS = (
    ("FLOAT32", "Float 32", "32-bit float depth"),
    ("FLOAT16", "Float 16", "16-bit float depth: half the memory, less precision"),
    ("RGBA8", "RGBA8 Packed", "Depth packed into four 8-bit channels (the classic encoding)"),
)

SPECULAR_ITEMS = (
    ("BLINN", "Blinn-Phong", "Normalised Blinn-Phong highlight (half vector)"),
    ("PHONG", "Phong", "Normalised Phong highlight (reflection vector)"),
)


def _redraw(self, context):
    """Property update: redraw every 3D viewport so Rendered shading shows the change at once."""
    screen = getattr(context, "screen", None)
    if screen is None:
        return
    for area in screen.areas:
        if area.type == "VIEW_3D":
            area.tag_redraw()


def _property_for(param):
    kw = {"name": param.label, "description": param.description, "update": _redraw}
    if param.type == "FLOAT":
        kw["default"] = param.default
        kw["subtype"] = param.subtype
        if param.min is not None:
            kw["min"] = param.min
        if param.max is not None:
            kw["max"] = param.max
        if param.soft_max is not None:
            kw["soft_max"] = param.soft_max
        return FloatProperty(**kw)
    if param.type == "INT":
        kw["default"] = param.default
        if param.min is not None:
            kw["min"] = int(param.min)
        if param.max is not None:
            kw["max"] = int(param.max)
        if param.soft_max is not None:
            kw["soft_max"] = int(param.soft_max)
        return IntProperty(**kw)
    if param.type == "BOOL":
        return BoolProperty(default=param.default, **kw)
    if param.type == "COLOR":
        return FloatVectorProperty(
            default=param.default, size=len(param.default), subtype="COLOR", min=0.0, soft_max=1.0, **kw
        )
    if param.type == "ENUM":
        return EnumProperty(items=param.items, default=param.default, **kw)
    if param.type == "IMAGE":
        return PointerProperty(type=bpy.types.Image, **kw)
    raise ValueError(f"unknown parameter type {param.type!r}")


def _effect_group(effect):
    """A PropertyGroup class holding one effect's parameters."""
    annotations = {p.name: _property_for(p) for p in effect.params}
    name = f"PENUMBRA_PG_{effect.id.lower()}"
    return type(name, (bpy.types.PropertyGroup,), {"__annotations__": annotations, "__doc__": effect.description})


EFFECT_GROUPS = {eid: _effect_group(cls) for eid, cls in EFFECTS.items()}

EFFECT_ITEMS = tuple(
    (eid, cls.label, cls.description, cls.icon, i) for i, (eid, cls) in enumerate(EFFECTS.items())
)


class PENUMBRA_PG_layer(bpy.types.PropertyGroup):
    """One post-process layer: an effect, its switches and its parameters."""

    __annotations__ = {
        "name": StringProperty(update=_redraw, name="Name", description="Layer name shown in the stack"),
        "effect": EnumProperty(update=_redraw, name="Effect", items=EFFECT_ITEMS, description="What this layer does"),
        "enabled": BoolProperty(update=_redraw, name="Enabled", default=True, description="Run this layer"),
        "solo": BoolProperty(
            update=_redraw,
            name="Solo",
            default=False,
            description="Show only the soloed layers (their enable switches are ignored)",
        ),
        "mix": FloatProperty(
        update=_redraw,
            name="Mix",
            default=1.0,
            min=0.0,
            max=1.0,
            subtype="FACTOR",
            description="Blend between the layer's input (0) and its result (1)",
        ),
        **{eid.lower(): PointerProperty(type=group) for eid, group in EFFECT_GROUPS.items()},
    }

    def params(self):
        return getattr(self, self.effect.lower())


class PENUMBRA_PG_scene(bpy.types.PropertyGroup):
    """Scene-wide Penumbra settings (``scene.penumbra``)."""

    shadow_filter: EnumProperty(
        update=_redraw,
        name="Shadow Filter", items=SHADOW_FILTER_ITEMS, default="PCF", description="How shadow edges are filtered"
    )
    shadow_map_size: IntProperty(
        update=_redraw,
        name="Shadow Map Size",
        default=2048,
        min=1,
        soft_max=8192,
        description="Texels per side of each shadow map (clamped to the GPU's maximum)",
    )
    shadow_samples: IntProperty(
        update=_redraw,
        name="Shadow Samples",
        default=16,
        min=8,
        max=64,
        step=8,
        description="Samples of the jittered-disk and PCSS filters (rounded down to a multiple of 8)",
    )
    shadow_filter_radius: FloatProperty(
        update=_redraw,
        name="Filter Radius",
        default=2.0,
        min=0.0,
        soft_max=16.0,
        max=32.0,
        description="Radius of the jittered-disk filter, in shadow-map texels",
    )
    shadow_depth_format: EnumProperty(
        update=_redraw, name="Depth Format", items=DEPTH_FORMAT_ITEMS, default="FLOAT32", description="How shadow depth is stored"
    )
    shadow_sun_fit: EnumProperty(
        update=_redraw,
        name="Sun Fit",
        items=(
            ("VIEW", "View", "Fit sun maps to what the camera sees: sharpest, redrawn when the view changes the fit"),
            ("SCENE", "Scene", "Fit sun maps to the whole scene: never redrawn for camera moves, coarser in large scenes"),
        ),
        default="VIEW",
        description="What a sun's shadow map covers",
    )
    shadow_early_out: BoolProperty(
        update=_redraw,
        name="Early Out",
        default=True,
        description="Jittered disk: skip the inner samples where the outer ring agrees",
    )
    pcf_kernel_size: IntProperty(
        update=_redraw,
        name="PCF Kernel", default=5, min=1, max=15, description="Width N of the NxN PCF kernel (made odd)"
    )
    pcf_spacing: FloatProperty(
        update=_redraw,
        name="PCF Spacing", default=1.0, min=0.0, soft_max=8.0, description="Distance between PCF taps, in texels"
    )
    shadow_bias: FloatProperty(
        update=_redraw,
        name="Constant Bias", default=0.5, min=0.0, soft_max=10.0, description="Depth bias in shadow-map texels"
    )
    shadow_slope_bias: FloatProperty(
        update=_redraw,
        name="Slope Bias",
        default=1.0,
        min=0.0,
        soft_max=10.0,
        description="Extra depth bias in texels per unit of tan(angle to the light)",
    )
    shadow_normal_offset: FloatProperty(
        update=_redraw,
        name="Normal Offset",
        default=1.0,
        min=0.0,
        soft_max=10.0,
        description="Offset of the lookup along the surface normal, in texels",
    )
    shadow_cull_front: BoolProperty(
        update=_redraw,
        name="Cull Front Faces",
        default=False,
        description="Draw only back faces into shadow maps (less acne on closed meshes)",
    )
    specular_model: EnumProperty(update=_redraw, name="Specular", items=SPECULAR_ITEMS, default="BLINN")
    layers: CollectionProperty(type=PENUMBRA_PG_layer, name="Post Layers")
    active_layer_index: IntProperty(update=_redraw, name="Active Layer", default=0, min=0)

    def render_settings(self, frame):
        """The plain settings a frame needs (the renderer never reads Blender properties)."""
        layers = []
        soloing = any(layer.solo for layer in self.layers)
        for layer in self.layers:
            enabled = layer.solo if soloing else layer.enabled
            if not enabled:
                layers.append((layer.effect, False, layer.mix, None))
                continue
            params = layer.params()
            values = {}
            for p in EFFECTS[layer.effect].params:
                v = getattr(params, p.name)
                values[p.name] = tuple(v) if p.type == "COLOR" else v
            layers.append((layer.effect, True, layer.mix, SimpleNamespace(**values)))
        return RenderSettings(
            shadow_filter=self.shadow_filter,
            shadow_map_size=self.shadow_map_size,
            pcf_kernel_size=self.pcf_kernel_size,
            pcf_spacing=self.pcf_spacing,
            shadow_bias=self.shadow_bias,
            shadow_slope_bias=self.shadow_slope_bias,
            shadow_normal_offset=self.shadow_normal_offset,
            shadow_cull_front=self.shadow_cull_front,
            shadow_samples=self.shadow_samples,
            shadow_filter_radius=self.shadow_filter_radius,
            shadow_depth_format=self.shadow_depth_format,
            shadow_early_out=self.shadow_early_out,
            shadow_sun_fit=self.shadow_sun_fit,
            specular_model=self.specular_model,
            frame=frame,
            layers=layers,
        )


class PENUMBRA_PG_light(bpy.types.PropertyGroup):
    """Per-light Penumbra settings (``light.penumbra``)."""

    bias_scale: FloatProperty(
        update=_redraw,
        name="Bias Scale",
        default=1.0,
        min=0.0,
        soft_max=10.0,
        description="Multiplies the scene's shadow biases for this light",
    )


classes = (*EFFECT_GROUPS.values(), PENUMBRA_PG_layer, PENUMBRA_PG_scene, PENUMBRA_PG_light)
_register_classes, _unregister_classes = bpy.utils.register_classes_factory(classes)


def register():
    _register_classes()
    bpy.types.Scene.penumbra = PointerProperty(type=PENUMBRA_PG_scene, name="Penumbra")
    bpy.types.Light.penumbra = PointerProperty(type=PENUMBRA_PG_light, name="Penumbra")


def unregister():
    del bpy.types.Light.penumbra
    del bpy.types.Scene.penumbra
    _unregister_classes()
