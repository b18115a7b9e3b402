"""Render-properties panels and the sidebar (N-panel) tab with the post-layer stack."""

import bpy
from bl_ui.properties_view_layer import (
    ViewLayerAOVPanelHelper,
    ViewLayerCryptomattePanelHelper,
    ViewLayerLightgroupsPanelHelper,
)

from ..engine import settings
from ..engine.enums import DEBUG_VIEW
from ..engine.post import EFFECTS


class PenumbraPanel:
    COMPAT_ENGINES = {"PENUMBRA"}
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"

    @classmethod
    def poll(cls, context):
        return context.scene is not None and context.scene.render.engine in cls.COMPAT_ENGINES

    def split_layout(self):
        """The panel's layout in Blender's property-split style (labels left, no decorators)."""
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        return layout


def draw_params(layout, group, params, section=None):
    """One row per declared ``Param`` of ``section`` (all when None), in declaration order,
    greyed out where the declaration says the current values make it irrelevant. A row with a
    ``switch`` carries that BOOL setting as its checkbox, as Cycles draws Noise Threshold."""
    shown = [p for p in params if section is None or p.section == section]
    switches = {p.switch for p in shown if p.switch}
    for p in shown:
        if p.name in switches:
            continue
        if p.switch:
            col = layout.column(heading=p.ui_label, align=True)
            row = col.row(align=True)
            row.prop(group, p.switch, text="")
            sub = row.row()
            sub.active = bool(getattr(group, p.switch)) and p.is_active(group, params)
            sub.prop(group, p.name, text="")
            continue
        row = layout.row()
        row.active = p.is_active(group, params)
        row.prop(group, p.name)


class _SettingsPanel(PenumbraPanel):
    """A Render Properties panel drawing one section of the scene settings."""

    bl_context = "render"
    section = None

    def draw(self, context):
        layout = self.split_layout()
        draw_params(layout, context.scene.penumbra, settings.SCENE_PARAMS, self.section)


class PENUMBRA_PT_sampling(_SettingsPanel, bpy.types.Panel):
    bl_label = "Sampling"
    section = settings.SAMPLING

    def draw(self, context):
        super().draw(context)
        self.layout.operator("penumbra.compare_cycles", icon="IMAGE")


class PENUMBRA_PT_sampling_viewport(_SettingsPanel, bpy.types.Panel):
    bl_label = "Viewport"
    bl_parent_id = "PENUMBRA_PT_sampling"
    section = settings.SAMPLING_VIEWPORT


class PENUMBRA_PT_sampling_render(_SettingsPanel, bpy.types.Panel):
    bl_label = "Render"
    bl_parent_id = "PENUMBRA_PT_sampling"
    section = settings.SAMPLING_RENDER


class PENUMBRA_PT_shadows(_SettingsPanel, bpy.types.Panel):
    bl_label = "Shadows"
    section = settings.SHADOWS


class PENUMBRA_PT_lighting(_SettingsPanel, bpy.types.Panel):
    bl_label = "Lighting"
    section = settings.LIGHTING


class PENUMBRA_PT_light_paths(_SettingsPanel, bpy.types.Panel):
    bl_label = "Light Paths"
    section = settings.LIGHT_PATHS


class PENUMBRA_PT_volumes(_SettingsPanel, bpy.types.Panel):
    bl_label = "Volumes"
    section = settings.VOLUMES


class PENUMBRA_PT_world(_SettingsPanel, bpy.types.Panel):
    """The world's light and its visibility, in World Properties (where EEVEE and Cycles put a
    world's settings); the values are the scene's, saved with it."""

    bl_label = "Penumbra"
    bl_context = "world"

    @classmethod
    def poll(cls, context):
        return super().poll(context) and context.world is not None

    section = settings.WORLD


class PENUMBRA_PT_world_sun(PENUMBRA_PT_world):
    """World > Sun, EEVEE's settings as Penumbra reads them (``frame/world/sun.py``): an
    Environment Texture's light above the threshold becomes a sun."""

    bl_label = "Sun"
    bl_parent_id = "PENUMBRA_PT_world"

    def draw(self, context):
        layout = self.split_layout()
        world = context.world
        layout.prop(world, "sun_threshold", text="Threshold")
        layout.prop(world, "sun_angle", text="Angle")
        layout.prop(world, "use_sun_shadow", text="Shadow")


class PENUMBRA_PT_viewport(_SettingsPanel, bpy.types.Panel):
    bl_label = "Viewport"
    section = settings.VIEWPORT
    bl_options = {"DEFAULT_CLOSED"}


class PENUMBRA_PT_simplify(_SettingsPanel, bpy.types.Panel):
    """Penumbra's part of Blender's Simplify panel, switched by its header checkbox."""

    bl_label = "Penumbra"
    bl_parent_id = "RENDER_PT_simplify"
    section = settings.SIMPLIFY

    def draw(self, context):
        self.layout.active = context.scene.render.use_simplify
        super().draw(context)


class PENUMBRA_PT_debug(_SettingsPanel, bpy.types.Panel):
    """Debug views (``scene.penumbra.debug_view``) in Render Properties."""

    bl_label = "Debug"
    section = settings.DEBUG
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        super().draw(context)
        view = context.scene.penumbra.debug_view
        if view != "NONE":
            self.layout.label(text=DEBUG_VIEW[view].legend, icon="INFO")


class PENUMBRA_PT_shading_debug(bpy.types.Panel):
    """The debug view in the viewport header's Shading popover, in Rendered shading (where
    Cycles puts its Render Pass)."""

    bl_space_type = "VIEW_3D"
    bl_region_type = "HEADER"
    bl_parent_id = "VIEW3D_PT_shading"
    bl_label = "Penumbra Debug"

    @classmethod
    def poll(cls, context):
        space = context.space_data
        return (
            context.scene is not None
            and context.scene.render.engine == "PENUMBRA"
            and getattr(getattr(space, "shading", None), "type", None) == "RENDERED"
        )

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        layout.prop(context.scene.penumbra, "debug_view", text="Debug View")


class PENUMBRA_PT_film(PenumbraPanel, bpy.types.Panel):
    bl_label = "Film"
    bl_context = "render"

    def draw(self, context):
        layout = self.split_layout()
        layout.prop(context.scene.render, "film_transparent")


class PENUMBRA_PT_motion_blur(PenumbraPanel, bpy.types.Panel):
    """Render > Motion Blur, Blender's own settings as Penumbra reads them
    (``engine/frame/motion.py``): Position, Shutter and the Shutter Curve below."""

    bl_label = "Motion Blur"
    bl_context = "render"
    bl_options = {"DEFAULT_CLOSED"}

    def draw_header(self, context):
        self.layout.prop(context.scene.render, "use_motion_blur", text="")

    def draw(self, context):
        layout = self.split_layout()
        rd = context.scene.render
        layout.active = rd.use_motion_blur
        col = layout.column()
        col.prop(rd, "motion_blur_position", text="Position")
        col.prop(rd, "motion_blur_shutter")


class PENUMBRA_PT_motion_blur_curve(PenumbraPanel, bpy.types.Panel):
    bl_label = "Shutter Curve"
    bl_context = "render"
    bl_parent_id = "PENUMBRA_PT_motion_blur"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        layout = self.layout
        rd = context.scene.render
        layout.active = rd.use_motion_blur
        layout.template_curve_mapping(rd, "motion_blur_shutter_curve")


class PENUMBRA_PT_passes(PenumbraPanel, bpy.types.Panel):
    """The passes Penumbra writes (Combined always)."""

    bl_label = "Passes"
    bl_context = "view_layer"

    def draw(self, context):
        layout = self.split_layout()
        view_layer = context.view_layer
        col = layout.column(heading="Include", align=True)
        col.prop(view_layer, "use_pass_z")
        col.prop(view_layer, "use_pass_mist")
        col.prop(view_layer, "use_pass_normal")
        col.prop(view_layer, "use_pass_position")
        col.prop(view_layer, "use_pass_object_index")
        col.prop(view_layer, "use_pass_material_index")
        col = layout.column(heading="Light", align=True)
        col.prop(view_layer, "use_pass_emit")
        col.prop(view_layer, "use_pass_environment")
        col.prop(view_layer, "use_pass_diffuse_color")
        col.prop(view_layer, "use_pass_glossy_color")
        col.prop(view_layer, "use_pass_transmission_color")
        col = layout.column(heading="Penumbra", align=True)
        draw_params(col, view_layer.penumbra, settings.VIEW_LAYER_PARAMS)


class PENUMBRA_PT_passes_aov(ViewLayerAOVPanelHelper, bpy.types.Panel):
    """The view layer's Shader AOVs (Blender's list), under Penumbra's passes."""

    bl_parent_id = "PENUMBRA_PT_passes"
    COMPAT_ENGINES = {"PENUMBRA"}


class PENUMBRA_PT_passes_cryptomatte(ViewLayerCryptomattePanelHelper, bpy.types.Panel):
    """Cryptomatte's kinds and levels (Blender's panel), under Penumbra's passes."""

    bl_parent_id = "PENUMBRA_PT_passes"
    COMPAT_ENGINES = {"PENUMBRA"}


class PENUMBRA_PT_passes_lightgroups(ViewLayerLightgroupsPanelHelper, bpy.types.Panel):
    """The view layer's light groups (Blender's list), under Penumbra's passes."""

    bl_parent_id = "PENUMBRA_PT_passes"
    COMPAT_ENGINES = {"PENUMBRA"}


class PENUMBRA_PT_object_lightgroup(PenumbraPanel, bpy.types.Panel):
    """Object > Shading > Light Group: the light group a light's light, or a surface's
    emission, is in (its view layer's light group pass)."""

    bl_label = "Light Group"
    bl_parent_id = "OBJECT_PT_shading"
    bl_context = "object"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        layout = self.split_layout()
        layout.prop_search(context.object, "lightgroup", context.view_layer, "lightgroups", text="Light Group")


class PENUMBRA_PT_world_lightgroup(PenumbraPanel, bpy.types.Panel):
    """World > Light Group: the light group the world's light is in."""

    bl_label = "Light Group"
    bl_context = "world"
    bl_options = {"DEFAULT_CLOSED"}

    @classmethod
    def poll(cls, context):
        return super().poll(context) and context.world is not None

    def draw(self, context):
        layout = self.split_layout()
        layout.prop_search(context.world, "lightgroup", context.view_layer, "lightgroups", text="Light Group")


class PENUMBRA_PT_light(PenumbraPanel, bpy.types.Panel):
    bl_label = "Penumbra"
    bl_context = "data"

    @classmethod
    def poll(cls, context):
        return super().poll(context) and context.light is not None

    def draw(self, context):
        layout = self.split_layout()
        influence = layout.column(align=True, heading="Influence")
        influence.prop(context.light, "diffuse_factor", text="Diffuse")
        influence.prop(context.light, "specular_factor", text="Specular")
        influence.prop(context.light, "volume_factor", text="Volume")
        layout.prop(context.light, "use_shadow")
        col = layout.column()
        col.active = context.light.use_shadow
        draw_params(col, context.light.penumbra, settings.LIGHT_PARAMS)


class PENUMBRA_PT_lightprobe(PenumbraPanel, bpy.types.Panel):
    """A Light Probe's settings Penumbra reads: a Plane probe's influence and clipping offset
    (``engine/frame/features/planar.py``), a Sphere probe's influence and clip range
    (``features/cubes.py``); a Volume probe says it is not used."""

    bl_label = "Probe"
    bl_context = "data"

    @classmethod
    def poll(cls, context):
        return super().poll(context) and getattr(context, "lightprobe", None) is not None

    def draw(self, context):
        layout = self.split_layout()
        probe = context.lightprobe
        col = layout.column()
        if probe.type == "PLANE":
            col.prop(probe, "influence_distance", text="Distance")
            col.prop(probe, "clip_start", text="Clipping Offset")
        elif probe.type == "SPHERE":
            col.prop(probe, "influence_type")
            col.prop(probe, "influence_distance", text="Radius" if probe.influence_type == "ELIPSOID" else "Size")
            col.prop(probe, "falloff")
            sub = col.column(align=True)
            sub.prop(probe, "clip_start", text="Clipping Start")
            sub.prop(probe, "clip_end", text="End")
        else:
            layout.label(text="Penumbra bakes no indirect light: Volume probes are not used", icon="INFO")


class PENUMBRA_PT_material(PenumbraPanel, bpy.types.Panel):
    """What Penumbra draws of the active material, and each part of its node tree it does not
    read (the same messages the render report gives)."""

    bl_label = "Penumbra"
    bl_context = "material"

    @classmethod
    def poll(cls, context):
        return super().poll(context) and getattr(context, "material", None) is not None

    def draw(self, context):
        from ..engine.scene.materials import material_from_blender, summary

        col = self.layout.column(align=True)
        for icon, text in summary(material_from_blender(context.material)):
            col.label(text=text, icon=icon)
        # Blender's own settings, as EEVEE reads them (saved in the .blend, undoable).
        col = self.layout.column(heading="Backface Culling")
        col.prop(context.material, "use_backface_culling", text="Camera")
        if hasattr(context.material, "use_backface_culling_shadow"):
            col.prop(context.material, "use_backface_culling_shadow", text="Shadow")
        if hasattr(context.material, "thickness_mode"):  # how light leaves a transmissive surface
            self.layout.prop(context.material, "thickness_mode", text="Thickness")


class PENUMBRA_UL_layers(bpy.types.UIList):
    def draw_item(self, context, layout, data, item, icon, active_data, active_propname, index):
        effect = EFFECTS.get(item.effect)
        row = layout.row(align=True)
        row.prop(item, "enabled", text="")
        row.prop(item, "name", text="", emboss=False, icon=effect.icon if effect else "NONE")
        row.prop(item, "solo", text="", icon="SOLO_ON" if item.solo else "SOLO_OFF", emboss=False)


class PENUMBRA_MT_layer_add(bpy.types.Menu):
    bl_label = "Add Post Layer"

    def draw(self, context):
        for eid, cls in EFFECTS.items():
            self.layout.operator("penumbra.layer_add", text=cls.label, icon=cls.icon).effect = eid


def draw_layer_stack(layout, context):
    s = context.scene.penumbra
    row = layout.row(align=True)
    row.menu("PENUMBRA_MT_post_presets", text=bpy.types.PENUMBRA_MT_post_presets.bl_label)
    row.operator("penumbra.post_preset_add", text="", icon="ADD")
    row.operator("penumbra.post_preset_add", text="", icon="REMOVE").remove_active = True
    row = layout.row()
    row.template_list("PENUMBRA_UL_layers", "", s, "layers", s, "active_layer_index", rows=4)
    col = row.column(align=True)
    col.menu("PENUMBRA_MT_layer_add", icon="ADD", text="")
    col.operator("penumbra.layer_remove", icon="REMOVE", text="")
    col.separator()
    col.operator("penumbra.layer_duplicate", icon="DUPLICATE", text="")
    col.separator()
    col.operator("penumbra.layer_move", icon="TRIA_UP", text="").direction = "UP"
    col.operator("penumbra.layer_move", icon="TRIA_DOWN", text="").direction = "DOWN"

    if 0 <= s.active_layer_index < len(s.layers):
        layer = s.layers[s.active_layer_index]
        box = layout.box()
        box.use_property_split = True
        box.use_property_decorate = False
        box.prop(layer, "mix", slider=True)
        draw_params(box, layer.params(), EFFECTS[layer.effect].params)


class PENUMBRA_PT_sidebar_layers(PenumbraPanel, bpy.types.Panel):
    bl_label = "Post Layers"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Penumbra"

    def draw(self, context):
        draw_layer_stack(self.layout, context)


class PENUMBRA_PT_render_layers(PenumbraPanel, bpy.types.Panel):
    bl_label = "Post Layers"
    bl_context = "render"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        draw_layer_stack(self.layout, context)


classes = (
    PENUMBRA_PT_material,
    PENUMBRA_PT_sampling,
    PENUMBRA_PT_sampling_viewport,
    PENUMBRA_PT_sampling_render,
    PENUMBRA_PT_film,
    PENUMBRA_PT_motion_blur,
    PENUMBRA_PT_motion_blur_curve,
    PENUMBRA_PT_passes,
    PENUMBRA_PT_passes_aov,
    PENUMBRA_PT_passes_cryptomatte,
    PENUMBRA_PT_passes_lightgroups,
    PENUMBRA_PT_object_lightgroup,
    PENUMBRA_PT_world_lightgroup,
    PENUMBRA_PT_shadows,
    PENUMBRA_PT_light,
    PENUMBRA_PT_lightprobe,
    PENUMBRA_PT_lighting,
    PENUMBRA_PT_light_paths,
    PENUMBRA_PT_volumes,
    PENUMBRA_PT_world,
    PENUMBRA_PT_world_sun,
    PENUMBRA_PT_viewport,
    PENUMBRA_PT_simplify,
    PENUMBRA_PT_debug,
    PENUMBRA_PT_shading_debug,
    PENUMBRA_UL_layers,
    PENUMBRA_MT_layer_add,
    PENUMBRA_PT_sidebar_layers,
    PENUMBRA_PT_render_layers,
)
register, unregister = bpy.utils.register_classes_factory(classes)
