"""Post-layer operators: add, remove, move, duplicate (all undoable)."""

import bpy
from bpy.props import EnumProperty

from ..engine.post import EFFECT_ENUM
from ..properties import redraw_viewports


def _settings(context):
    return context.scene.penumbra


def _copy_group(src, dst):
    """Copy every property of a PropertyGroup, recursing into pointer properties."""
    for prop in src.bl_rna.properties:
        ident = prop.identifier
        if ident == "rna_type":
            continue
        if prop.type == "POINTER" and isinstance(getattr(src, ident), bpy.types.PropertyGroup):
            _copy_group(getattr(src, ident), getattr(dst, ident))
        elif not prop.is_readonly:
            setattr(dst, ident, getattr(src, ident))


class _LayerOperator:
    bl_options = {"REGISTER", "UNDO"}

    def finish(self, context):
        redraw_viewports(self, context)
        return {"FINISHED"}

    @classmethod
    def poll(cls, context):
        return context.scene is not None and hasattr(context.scene, "penumbra")


class _ActiveLayerOperator(_LayerOperator):
    @classmethod
    def poll(cls, context):
        if not super().poll(context):
            return False
        s = _settings(context)
        return 0 <= s.active_layer_index < len(s.layers)


class PENUMBRA_OT_layer_add(_LayerOperator, bpy.types.Operator):
    """Add a post-process layer above the active one"""

    bl_idname = "penumbra.layer_add"
    bl_label = "Add Post Layer"

    effect: EnumProperty(name="Effect", items=EFFECT_ENUM.blender_items())

    def execute(self, context):
        s = _settings(context)
        layer = s.layers.add()
        layer.effect = self.effect
        layer.name = EFFECT_ENUM[self.effect].label
        new = len(s.layers) - 1
        target = min(s.active_layer_index, new) if len(s.layers) > 1 else 0
        s.layers.move(new, target)
        s.active_layer_index = target
        return self.finish(context)


class PENUMBRA_OT_layer_remove(_ActiveLayerOperator, bpy.types.Operator):
    """Remove the active post-process layer"""

    bl_idname = "penumbra.layer_remove"
    bl_label = "Remove Post Layer"

    def execute(self, context):
        s = _settings(context)
        s.layers.remove(s.active_layer_index)
        s.active_layer_index = max(0, min(s.active_layer_index, len(s.layers) - 1))
        return self.finish(context)


class PENUMBRA_OT_layer_move(_ActiveLayerOperator, bpy.types.Operator):
    """Move the active post-process layer up or down the stack"""

    bl_idname = "penumbra.layer_move"
    bl_label = "Move Post Layer"

    direction: EnumProperty(
        name="Direction", items=(("UP", "Up", "Towards the top (runs earlier)"), ("DOWN", "Down", "Towards the bottom"))
    )

    def execute(self, context):
        s = _settings(context)
        i = s.active_layer_index
        j = i - 1 if self.direction == "UP" else i + 1
        if not 0 <= j < len(s.layers):
            return {"CANCELLED"}
        s.layers.move(i, j)
        s.active_layer_index = j
        return self.finish(context)


class PENUMBRA_OT_layer_duplicate(_ActiveLayerOperator, bpy.types.Operator):
    """Duplicate the active post-process layer with all its settings"""

    bl_idname = "penumbra.layer_duplicate"
    bl_label = "Duplicate Post Layer"

    def execute(self, context):
        s = _settings(context)
        i = s.active_layer_index
        new = s.layers.add()
        _copy_group(s.layers[i], new)
        new.name = s.layers[i].name + " copy"
        s.layers.move(len(s.layers) - 1, i + 1)
        s.active_layer_index = i + 1
        return self.finish(context)


classes = (PENUMBRA_OT_layer_add, PENUMBRA_OT_layer_remove, PENUMBRA_OT_layer_move, PENUMBRA_OT_layer_duplicate)
register, unregister = bpy.utils.register_classes_factory(classes)
