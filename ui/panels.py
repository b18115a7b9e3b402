"""Render-properties panels and the sidebar (N-panel) tab with the post-layer stack."""

import bpy

from ..engine.post import EFFECTS


class PenumbraPanel:
    COMPAT_ENGINES = {"PENUMBRA"}

    @classmethod
    def poll(cls, context):
        return context.scene is not None and context.scene.render.engine in cls.COMPAT_ENGINES


class PENUMBRA_PT_shadows(PenumbraPanel, bpy.types.Panel):
    bl_label = "Shadows"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "render"

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        s = context.scene.penumbra
        layout.prop(s, "shadow_filter")
        layout.prop(s, "shadow_map_size")
        layout.prop(s, "shadow_depth_format")
        layout.prop(s, "shadow_sun_fit")
        col = layout.column()
        col.active = s.shadow_filter == "PCF"
        col.prop(s, "pcf_kernel_size")
        col.prop(s, "pcf_spacing")
        col = layout.column()
        col.active = s.shadow_filter in {"JITTER", "PCSS"}
        col.prop(s, "shadow_samples")
        sub = col.column()
        sub.active = s.shadow_filter == "JITTER"
        sub.prop(s, "shadow_filter_radius")
        sub.prop(s, "shadow_early_out")
        col = layout.column(align=True)
        col.prop(s, "shadow_bias")
        col.prop(s, "shadow_slope_bias")
        col.prop(s, "shadow_normal_offset")
        layout.prop(s, "shadow_cull_front")


class PENUMBRA_PT_light(PenumbraPanel, bpy.types.Panel):
    bl_label = "Penumbra"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "data"

    @classmethod
    def poll(cls, context):
        return super().poll(context) and context.light is not None

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        layout.prop(context.light, "use_shadow")
        col = layout.column()
        col.active = context.light.use_shadow
        col.prop(context.light.penumbra, "bias_scale")


class PENUMBRA_PT_lighting(PenumbraPanel, bpy.types.Panel):
    bl_label = "Lighting"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "render"

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        layout.prop(context.scene.penumbra, "specular_model")


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
        params = layer.params()
        for p in EFFECTS[layer.effect].params:
            box.prop(params, p.name)


class PENUMBRA_PT_sidebar_layers(PenumbraPanel, bpy.types.Panel):
    bl_label = "Post Layers"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Penumbra"

    def draw(self, context):
        draw_layer_stack(self.layout, context)


class PENUMBRA_PT_render_layers(PenumbraPanel, bpy.types.Panel):
    bl_label = "Post Layers"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "render"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        draw_layer_stack(self.layout, context)


classes = (
    PENUMBRA_PT_shadows,
    PENUMBRA_PT_light,
    PENUMBRA_PT_lighting,
    PENUMBRA_UL_layers,
    PENUMBRA_MT_layer_add,
    PENUMBRA_PT_sidebar_layers,
    PENUMBRA_PT_render_layers,
)
register, unregister = bpy.utils.register_classes_factory(classes)
