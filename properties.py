"""Penumbra's Blender properties, generated from the declarations in ``engine/settings.py``
(scene and light settings) and ``engine/post`` (each effect's parameters).

``scene.penumbra`` holds the scene settings and the post-layer collection; each layer carries
one PointerProperty per effect (``layer.blur.radius``, ``layer.vignette.color``, ...). Nothing
here names a setting: add one by adding its ``Param`` row.

Saved files carry ``schema_version``; loading a file runs the upgrade steps of
``engine/settings.py`` so renamed settings keep their values.
"""

import sys
from types import SimpleNamespace

import bpy
from bpy.app.handlers import persistent
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

from .engine import settings
from .engine.post import EFFECT_ENUM, EFFECTS, Layer


def redraw_viewports(self, context):
    """Property update: redraw every 3D viewport so Rendered shading shows the change at once."""
    screen = getattr(context, "screen", None)
    if screen is None:
        return
    for area in screen.areas:
        if area.type == "VIEW_3D":
            area.tag_redraw()


def _limits(param, cast):
    kw = {}
    for key in ("min", "max", "soft_min", "soft_max", "step"):
        value = getattr(param, key)
        if value is not None:
            kw[key] = cast(value)
    return kw


def update_passes(self, context):
    """Property update of a pass switch: Blender re-asks the engine which passes exist."""
    view_layer = getattr(context, "view_layer", None)
    if view_layer is not None:
        view_layer.update_render_passes()


def property_for(param, update=redraw_viewports):
    """The bpy property of one ``settings.Param``."""
    kw = {"name": param.ui_label, "description": param.description, "update": update}
    if param.unit == "PIXELS":
        kw["subtype"] = "PIXEL"
    if param.type == "FLOAT":
        kw.setdefault("subtype", param.subtype)
        if param.precision is not None:
            kw["precision"] = param.precision
        return FloatProperty(default=param.default, **_limits(param, float), **kw)
    if param.type == "INT":
        return IntProperty(default=param.default, **_limits(param, int), **kw)
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


def group_class(name, params, doc, extra=None, methods=None, update=redraw_viewports):
    """A PropertyGroup class with one property per ``Param`` (plus ``extra`` annotations)."""
    annotations = {p.name: property_for(p, update) for p in params}
    annotations.update(extra or {})
    return type(name, (bpy.types.PropertyGroup,), {"__annotations__": annotations, "__doc__": doc, **(methods or {})})


def _schema_version():
    return IntProperty(
        name="Schema Version",
        default=0,
        min=0,
        options={"HIDDEN"},
        description="Layout version of these saved settings (upgraded on load)",
    )


EFFECT_GROUPS = {
    eid: group_class(f"PENUMBRA_PG_{eid.lower()}", cls.params, cls.description) for eid, cls in EFFECTS.items()
}


def _layer_params(self):
    return getattr(self, self.effect.lower())


PENUMBRA_PG_layer = group_class(
    "PENUMBRA_PG_layer",
    (),
    "One post-process layer: an effect, its switches and its parameters.",
    extra={
        "name": StringProperty(update=redraw_viewports, name="Name", description="Layer name shown in the stack"),
        "effect": EnumProperty(
            update=redraw_viewports,
            name="Effect",
            items=EFFECT_ENUM.blender_items(),
            description="What this layer does",
        ),
        "enabled": BoolProperty(update=redraw_viewports, name="Enabled", default=True, description="Run this layer"),
        "solo": BoolProperty(
            update=redraw_viewports,
            name="Solo",
            default=False,
            description="Show only the soloed layers (their enable switches are ignored)",
        ),
        "mix": FloatProperty(
            update=redraw_viewports,
            name="Mix",
            default=1.0,
            min=0.0,
            max=1.0,
            subtype="FACTOR",
            description="Blend between the layer's input (0) and its result (1)",
        ),
        **{eid.lower(): PointerProperty(type=group) for eid, group in EFFECT_GROUPS.items()},
    },
    methods={"params": _layer_params},
)


def _render_settings(self, frame, film_transparent=False, pixel_scale=1.0, use_simplify=False):
    """The plain settings a frame needs (the renderer never reads Blender properties)."""
    soloing = any(layer.solo for layer in self.layers)
    layers = []
    for layer in self.layers:
        enabled = layer.solo if soloing else layer.enabled
        # Raw values: the post stack clamps them to their declared ranges once, per frame.
        params = None
        if enabled:
            group = layer.params()
            params = SimpleNamespace(**{p.name: getattr(group, p.name) for p in EFFECTS[layer.effect].params})
        layers.append(Layer(layer.effect, enabled, layer.mix, params))
    return settings.render_settings(
        self,
        frame=frame,
        film_transparent=film_transparent,
        pixel_scale=pixel_scale,
        use_simplify=use_simplify,
        layers=layers,
    )


PENUMBRA_PG_scene = group_class(
    "PENUMBRA_PG_scene",
    settings.SCENE_PARAMS,
    "Scene-wide Penumbra settings (``scene.penumbra``).",
    extra={
        "layers": CollectionProperty(type=PENUMBRA_PG_layer, name="Post Layers"),
        "active_layer_index": IntProperty(update=redraw_viewports, name="Active Layer", default=0, min=0),
        "schema_version": _schema_version(),
    },
    methods={"render_settings": _render_settings},
)

PENUMBRA_PG_light = group_class(
    "PENUMBRA_PG_light",
    settings.LIGHT_PARAMS,
    "Per-light Penumbra settings (``light.penumbra``).",
    extra={"schema_version": _schema_version()},
)


PENUMBRA_PG_view_layer = group_class(
    "PENUMBRA_PG_view_layer",
    settings.VIEW_LAYER_PARAMS,
    "Per-view-layer Penumbra settings (``view_layer.penumbra``): its optional passes.",
    update=update_passes,
)


# --- versioning ---------------------------------------------------------------------------


def stored_properties(group):
    """The stored values of a registered PropertyGroup as a mapping (Blender 5.x keeps them
    apart from custom properties; 4.5 exposes them on the group itself)."""
    getter = getattr(group, "bl_system_properties_get", None)
    if getter is None:
        return group
    return getter(do_create=True) if "do_create" in getter.__doc__ else getter()


def upgrade_file(scene_upgrades=None, light_upgrades=None, current=None):
    """Upgrade every scene's and light's stored settings to this version's layout. Returns
    [(datablock name, saved version, changes)] for what was upgraded or is newer."""
    current = settings.SCHEMA_VERSION if current is None else current
    report = []
    targets = [(s, s.penumbra, scene_upgrades or settings.SCENE_UPGRADES) for s in bpy.data.scenes]
    targets += [(lt, lt.penumbra, light_upgrades or settings.LIGHT_UPGRADES) for lt in bpy.data.lights]
    for owner, group, upgrades in targets:
        if owner.library is not None:
            continue  # linked data is read-only here; its own file is upgraded when opened
        stored = stored_properties(group)
        if stored is None or len(stored.keys()) == 0:
            group.schema_version = current  # nothing saved: nothing to upgrade
            continue
        saved, changes = settings.upgrade(stored, upgrades, current)
        if saved != current or changes:
            report.append((owner.name, saved, changes))
        if saved > current:
            print(
                f"Penumbra: '{owner.name}' was saved by a newer Penumbra (settings layout {saved}, "
                f"this version reads {current}); settings it does not know are kept but ignored",
                file=sys.stderr,
            )
    return report


@persistent
def _on_load_post(*_args):
    upgrade_file()


@persistent
def _on_save_pre(*_args):
    for owner in (*bpy.data.scenes, *bpy.data.lights):
        if owner.library is None and owner.penumbra.schema_version < settings.SCHEMA_VERSION:
            owner.penumbra.schema_version = settings.SCHEMA_VERSION


classes = (*EFFECT_GROUPS.values(), PENUMBRA_PG_layer, PENUMBRA_PG_scene, PENUMBRA_PG_light, PENUMBRA_PG_view_layer)
_register_classes, _unregister_classes = bpy.utils.register_classes_factory(classes)


def register():
    _register_classes()
    bpy.types.Scene.penumbra = PointerProperty(type=PENUMBRA_PG_scene, name="Penumbra")
    bpy.types.Light.penumbra = PointerProperty(type=PENUMBRA_PG_light, name="Penumbra")
    bpy.types.ViewLayer.penumbra = PointerProperty(type=PENUMBRA_PG_view_layer, name="Penumbra")
    bpy.app.handlers.load_post.append(_on_load_post)
    bpy.app.handlers.save_pre.append(_on_save_pre)


def unregister():
    for handlers, fn in ((bpy.app.handlers.load_post, _on_load_post), (bpy.app.handlers.save_pre, _on_save_pre)):
        if fn in handlers:
            handlers.remove(fn)
    del bpy.types.ViewLayer.penumbra
    del bpy.types.Light.penumbra
    del bpy.types.Scene.penumbra
    _unregister_classes()
