"""Which of Blender's own Properties-editor panels Penumbra shows.

As Blender's own add-on engines do: every panel of the generic render engine
(``BLENDER_RENDER`` in its ``COMPAT_ENGINES``) minus the features Penumbra ignores, plus the
few EEVEE panels that edit what Penumbra reads. What is shown is what works.
"""

import bpy

ENGINE = "PENUMBRA"

# Generic panels of features Penumbra does not render (by name prefix or full name).
EXCLUDE_PREFIXES = (
    "DATA_PT_lightprobe",  # light probes: Penumbra's own panel shows what a Plane probe sets
    "RENDER_PT_freestyle",  # Freestyle lines
    "VIEWLAYER_PT_freestyle",
    "MATERIAL_PT_freestyle",
    "RENDER_PT_gpencil",  # Grease Pencil objects are not drawn
    "RENDER_PT_grease_pencil",
    "DATA_PT_volume_render",  # volumes are not drawn
)
EXCLUDE = {
    "DATA_PT_light",  # the generic light panel repeats the type switch of DATA_PT_EEVEE_light
    "NODE_DATA_PT_light",  # light node trees are not read
}

# EEVEE panels whose settings Penumbra reads.
INCLUDE = {
    "DATA_PT_EEVEE_light",  # type, colour, power, radius, spot size and blend
    "DATA_PT_context_lightprobe",  # the probe's datablock (its settings: PENUMBRA_PT_lightprobe)
    "EEVEE_MATERIAL_PT_context_material",
    "EEVEE_MATERIAL_PT_surface",  # the Principled BSDF Penumbra reads
    "EEVEE_WORLD_PT_surface",  # the world colour (ambient)
    "EEVEE_WORLD_PT_mist",  # the Mist pass's start, depth and falloff
    "MATERIAL_PT_viewport",  # viewport display colour: the fallback material
    # Object > Shading > Shadow Terminator: Geometry Offset and Shading Offset (as for Cycles),
    # plus EEVEE's Normal Offset, drawn by ``draw_normal_offset`` (Blender's panel shows it for
    # EEVEE only).
    "OBJECT_PT_shadow_terminator",
    "WORLD_PT_viewport_display",
    "DATA_PT_camera_dof",  # depth of field by lens sampling (engine/frame/lens.py)
    "DATA_PT_camera_dof_aperture",  # f-stop, blades, rotation, ratio
}


def wanted(panel):
    name = panel.__name__
    engines = getattr(panel, "COMPAT_ENGINES", None)
    if engines is None:
        return False
    if name in INCLUDE:
        return True
    if "BLENDER_RENDER" not in engines:
        return False
    return name not in EXCLUDE and not name.startswith(EXCLUDE_PREFIXES)


def panels():
    return [p for p in bpy.types.Panel.__subclasses__() if wanted(p)]


_added = []
_hooked = []


def draw_normal_offset(self, context):
    """EEVEE's Normal Offset, which Penumbra honours too, below Blender's own rows."""
    if context.engine != ENGINE or context.object is None:
        return
    layout = self.layout
    layout.use_property_split = True
    layout.prop(context.object, "shadow_terminator_normal_offset", text="Normal Offset")


def register():
    for panel in panels():
        if ENGINE not in panel.COMPAT_ENGINES:
            panel.COMPAT_ENGINES.add(ENGINE)
            _added.append(panel)
    terminator = getattr(bpy.types, "OBJECT_PT_shadow_terminator", None)
    if terminator is not None:
        terminator.append(draw_normal_offset)
        _hooked.append(terminator)


def unregister():
    for panel in _added:
        panel.COMPAT_ENGINES.discard(ENGINE)
    _added.clear()
    for panel in _hooked:
        panel.remove(draw_normal_offset)
    _hooked.clear()
