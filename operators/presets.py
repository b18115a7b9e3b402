"""Post-stack presets, the way Blender does presets elsewhere: small Python files run by
``script.execute_preset``, listed by a preset menu, added and removed from the panel header.

Shipped looks live in the extension's ``presets/post_stack/``; user presets in Blender's user
scripts folder under ``presets/penumbra/post_stack/``.
"""

import json
from pathlib import Path

import bpy
from bpy.props import BoolProperty, StringProperty

from ..engine.post import EFFECTS
from ..engine.post.stack_data import stack_data, validate
from ..properties import redraw_viewports

PRESET_SUBDIR = "penumbra/post_stack"
SHIPPED_DIR = Path(__file__).resolve().parent.parent / "presets" / "post_stack"


def user_preset_dir(create=False):
    path = bpy.utils.user_resource("SCRIPTS", path=f"presets/{PRESET_SUBDIR}", create=create)
    return Path(path) if path else None


def preset_source(settings):
    """Python source of a preset that rebuilds ``settings.layers`` exactly (order, switches,
    solo, parameters). The stack travels as data through ``penumbra.post_stack_apply``, which
    validates all of it before it changes anything."""
    # JSON escapes every quote inside its strings, so it never holds three quotes in a row.
    data = json.dumps(stack_data(settings.layers, EFFECTS), indent=1)
    return f'import bpy\n\nSTACK = r"""\n{data}\n"""\n\nbpy.ops.penumbra.post_stack_apply(stack=STACK)\n'


def apply_stack(settings, layers, images):
    """Replace ``settings.layers`` by validated ``layers`` (``stack_data.validate``)."""
    settings.layers.clear()
    for entry in layers:
        layer = settings.layers.add()
        layer.effect = entry["effect"]
        for key in ("name", "enabled", "solo", "mix"):
            if key in entry:
                setattr(layer, key, entry[key])
        group = layer.params()
        kinds = {p.name: p.type for p in EFFECTS[entry["effect"]].params}
        for name, value in entry["params"].items():
            if kinds[name] == "IMAGE":
                value = images.get(value) if value is not None else None
            setattr(group, name, value)
    settings.active_layer_index = 0


class PENUMBRA_OT_post_stack_apply(bpy.types.Operator):
    """Replace the post-layer stack by a preset's layers (validated first: on any error the
    stack is left as it was)"""

    bl_idname = "penumbra.post_stack_apply"
    bl_label = "Apply Post Stack"
    bl_options = {"REGISTER", "UNDO", "INTERNAL"}

    stack: StringProperty(name="Stack", description="The stack as JSON (see engine/post/stack_data.py)")

    def execute(self, context):
        try:
            data = json.loads(self.stack)
        except ValueError as exc:
            self.report({"ERROR"}, f"Penumbra: the preset is not readable: {exc}")
            return {"CANCELLED"}
        layers, errors, warnings = validate(data, EFFECTS)
        images = {}
        for entry in layers:
            kinds = {p.name: p.type for p in EFFECTS[entry["effect"]].params}
            for name, value in entry["params"].items():
                if kinds[name] == "IMAGE" and value is not None:
                    images[value] = bpy.data.images.get(value)
                    if images[value] is None:
                        warnings.append(f"{entry['effect']}: image {value!r} is not in this file; left empty")
        if errors:
            self.report({"ERROR"}, "Penumbra: preset not applied, the stack is unchanged: " + "; ".join(errors))
            return {"CANCELLED"}
        apply_stack(context.scene.penumbra, layers, images)
        for message in warnings:
            self.report({"WARNING"}, f"Penumbra: preset: {message}")
        redraw_viewports(self, context)
        return {"FINISHED"}


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


classes = (PENUMBRA_OT_post_stack_apply, PENUMBRA_MT_post_presets, PENUMBRA_OT_post_preset_add)
register, unregister = bpy.utils.register_classes_factory(classes)
