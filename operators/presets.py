"""Post-stack presets, the way Blender does presets elsewhere: small Python files run by
``script.execute_preset``, listed by a preset menu, added and removed from the panel header.

Shipped looks live in the extension's ``presets/post_stack/``; user presets in Blender's user
scripts folder under ``presets/penumbra/post_stack/``.
"""

from pathlib import Path

import bpy
from bpy.props import BoolProperty, StringProperty

from ..engine.post import EFFECTS

PRESET_SUBDIR = "penumbra/post_stack"
SHIPPED_DIR = Path(__file__).resolve().parent.parent / "presets" / "post_stack"


def user_preset_dir(create=False):
    path = bpy.utils.user_resource("SCRIPTS", path=f"presets/{PRESET_SUBDIR}", create=create)
    return Path(path) if path else None


def _literal(param, value):
    if param.type == "IMAGE":
        return f"bpy.data.images.get({value.name!r})" if value is not None else "None"
    if param.type == "COLOR":
        return repr(tuple(round(float(v), 6) for v in value))
    if param.type == "FLOAT":
        return repr(round(float(value), 6))
    return repr(value)


def preset_source(settings):
    """Python source that rebuilds ``settings.layers`` exactly (order, switches, parameters)."""
    lines = [
        "import bpy",
        "s = bpy.context.scene.penumbra",
        "s.layers.clear()",
    ]
    for layer in settings.layers:
        lines.append("layer = s.layers.add()")
        lines.append(f"layer.effect = {layer.effect!r}")
        lines.append(f"layer.name = {layer.name!r}")
        lines.append(f"layer.enabled = {bool(layer.enabled)!r}")
        lines.append(f"layer.mix = {round(float(layer.mix), 6)!r}")
        group = layer.params()
        for param in EFFECTS[layer.effect].params:
            value = _literal(param, getattr(group, param.name))
            lines.append(f"layer.{layer.effect.lower()}.{param.name} = {value}")
    lines.append("s.active_layer_index = 0")
    return "\n".join(lines) + "\n"


class PENUMBRA_MT_post_presets(bpy.types.Menu):
    bl_label = "Post Presets"
    preset_subdir = PRESET_SUBDIR
    preset_operator = "script.execute_preset"

    def draw(self, context):
        paths = [str(SHIPPED_DIR)]
        user = user_preset_dir()
        if user is not None and user.is_dir():
            paths.append(str(user))
        self.path_menu(
            paths,
            self.preset_operator,
            props_default={"menu_idname": self.bl_idname},
            filter_ext=lambda ext: ext.lower() == ".py",
        )


class PENUMBRA_OT_post_preset_add(bpy.types.Operator):
    """Save the post-layer stack as a preset (or delete a saved one)"""

    bl_idname = "penumbra.post_preset_add"
    bl_label = "Add Post Preset"
    bl_options = {"REGISTER"}

    name: StringProperty(name="Name", description="Preset name", default="")
    remove_active: BoolProperty(default=False, options={"HIDDEN", "SKIP_SAVE"})

    def invoke(self, context, event):
        if self.remove_active:
            return self.execute(context)
        return context.window_manager.invoke_props_dialog(self)

    def execute(self, context):
        folder = user_preset_dir(create=True)
        if self.remove_active:
            name = bpy.path.clean_name(PENUMBRA_MT_post_presets.bl_label)
            path = folder / f"{name}.py"
            if not path.is_file():
                self.report({"WARNING"}, "Only user presets can be removed")
                return {"CANCELLED"}
            path.unlink()
            PENUMBRA_MT_post_presets.bl_label = "Post Presets"
            return {"FINISHED"}
        name = bpy.path.clean_name(self.name.strip())
        if not name:
            self.report({"ERROR"}, "Penumbra: a preset needs a name")
            return {"CANCELLED"}
        path = folder / f"{name}.py"
        path.write_text(preset_source(context.scene.penumbra), encoding="utf-8")
        PENUMBRA_MT_post_presets.bl_label = bpy.path.display_name(name)
        self.report({"INFO"}, f"Saved post preset {path}")
        return {"FINISHED"}


classes = (PENUMBRA_MT_post_presets, PENUMBRA_OT_post_preset_add)
register, unregister = bpy.utils.register_classes_factory(classes)
