"""Compare with Cycles: the scene rendered by Penumbra and by Cycles at the same sample count,
side by side with their per-pixel error in one image, "Penumbra vs Cycles".

Each engine renders twice through ``render.render``: as the scene is, and with every light's
shadow switched off. Shadow visibility is the first over the second, in luminance, so light
units and falloff cancel and only the shadow term remains; the same measure for both engines.
Cycles renders direct light only by default (no bounces, no caustics, no denoiser, no adaptive
sampling), the light Penumbra computes; ``mode='FULL'`` keeps the scene's Cycles settings but
the sample count.

The numbers (shadow IoU, mean errors, render times) go to the report and to the image's
custom properties (``image["iou"]``, ...): Blender images hold no other metadata from Python.
Every setting the compare touches is restored, whatever happens; a cancel (Esc during a render,
or ``request_cancel()``) leaves no image behind.
"""

import os
import tempfile
import time

import bpy
import numpy as np
from bpy.props import EnumProperty, IntProperty

IMAGE_NAME = "Penumbra vs Cycles"
LUMA = np.array([0.2126, 0.7152, 0.0722])  # Rec. 709 luminance of scene-linear RGB
EDGE = 0.5  # shadowed: visibility below this (the IoU's regions)
VALID = 0.02  # visibility is measured where the unshadowed image exceeds this x its 99th percentile

# Viridis (matplotlib's colour map), 17 evenly spaced entries in sRGB, interpolated linearly.
VIRIDIS = np.array(
    [
        (0.2670, 0.0049, 0.3294),
        (0.2823, 0.0950, 0.4173),
        (0.2788, 0.1755, 0.4834),
        (0.2590, 0.2515, 0.5247),
        (0.2297, 0.3224, 0.5457),
        (0.1994, 0.3876, 0.5546),
        (0.1727, 0.4488, 0.5579),
        (0.1490, 0.5081, 0.5572),
        (0.1276, 0.5669, 0.5506),
        (0.1206, 0.6258, 0.5335),
        (0.1579, 0.6838, 0.5017),
        (0.2461, 0.7389, 0.4520),
        (0.3692, 0.7889, 0.3829),
        (0.5160, 0.8312, 0.2943),
        (0.6785, 0.8637, 0.1895),
        (0.8456, 0.8873, 0.0997),
        (0.9932, 0.9062, 0.1439),
    ]
)
INVALID_COLOR = (0.05, 0.05, 0.05)  # pixels where shadow visibility is not defined (linear)

_cancel = {"requested": False}


def request_cancel(*_args):
    """Stop the running compare at its next step (also Blender's ``render_cancel`` handler)."""
    _cancel["requested"] = True


def colormap(values):
    """Scene-linear RGB (..., 3) of ``values`` in 0..1 on viridis (the sRGB table decoded, so
    Blender's Standard view shows the map's own colours)."""
    x = np.clip(np.nan_to_num(np.asarray(values, np.float64), nan=0.0), 0.0, 1.0) * (len(VIRIDIS) - 1)
    i = np.minimum(x.astype(int), len(VIRIDIS) - 2)
    t = (x - i)[..., None]
    srgb = VIRIDIS[i] * (1.0 - t) + VIRIDIS[i + 1] * t
    return np.where(srgb <= 0.04045, srgb / 12.92, ((srgb + 0.055) / 1.055) ** 2.4)


def luminance(rgba):
    return np.asarray(rgba, np.float64)[..., :3] @ LUMA


def visibility(shadowed, unshadowed):
    """Shadowed / unshadowed luminance per pixel, clipped to 0..1; NaN where the light does not
    reach (unshadowed below VALID x its 99th percentile: back faces, the background)."""
    level = float(np.percentile(unshadowed, 99)) if unshadowed.size else 0.0
    valid = unshadowed > VALID * level if level > 0 else np.zeros(unshadowed.shape, bool)
    vis = np.full(unshadowed.shape, np.nan)
    vis[valid] = np.clip(shadowed[valid] / unshadowed[valid], 0.0, 1.0)
    return vis


def shadow_iou(vis, ref):
    """Intersection over union of the shadowed regions (visibility < EDGE) over the pixels
    valid in both; 1.0 when neither has a shadow."""
    valid = np.isfinite(vis) & np.isfinite(ref)
    a, b = vis[valid] < EDGE, ref[valid] < EDGE
    union = int((a | b).sum())
    return float((a & b).sum() / union) if union else 1.0


class Settings:
    """Every setting the compare changes: (owner, attribute, old value), restored in reverse."""

    def __init__(self):
        self.saved = []

    def record(self, owner, attr):
        self.saved.append((owner, attr, getattr(owner, attr)))

    def set(self, owner, attr, value):
        self.record(owner, attr)
        setattr(owner, attr, value)

    def restore(self):
        while self.saved:
            owner, attr, value = self.saved.pop()
            if getattr(owner, attr) != value:
                setattr(owner, attr, value)


def _world_emits(world):
    if world is None:
        return False
    if getattr(world, "use_nodes", False) and world.node_tree is not None:
        for node in world.node_tree.nodes:
            if node.bl_idname == "ShaderNodeBackground":
                color, strength = node.inputs["Color"], node.inputs["Strength"]
                if color.is_linked or strength.is_linked:
                    return True
                if max(color.default_value[:3]) * strength.default_value > 0:
                    return True
        return False
    return max(world.color) > 0


def scene_lights(context):
    return [ob for ob in context.view_layer.objects if ob.type == "LIGHT" and not ob.hide_render]


class PENUMBRA_OT_compare_cycles(bpy.types.Operator):
    """Render the scene with Penumbra and with Cycles at the same sample count; one image
    shows both and their per-pixel error, the report the shadow IoU, mean errors and times"""

    bl_idname = "penumbra.compare_cycles"
    bl_label = "Compare with Cycles"
    bl_options = {"REGISTER"}

    samples: IntProperty(name="Samples", description="Samples per pixel of both renders", default=64, min=1, max=4096)
    mode: EnumProperty(
        name="Cycles",
        items=(
            ("DIRECT", "Direct Light", "Cycles with no bounces, caustics, denoiser or adaptive sampling"),
            ("FULL", "Full", "Cycles with the scene's own settings (only the sample count set)"),
        ),
        default="DIRECT",
    )
    error: EnumProperty(
        name="Error",
        items=(
            ("IMAGE", "Image", "Absolute luminance difference, relative to the reference's bright level"),
            ("SHADOW", "Shadow", "Absolute difference of shadow visibility"),
        ),
        default="IMAGE",
    )
    resolution_percentage: IntProperty(
        name="Resolution %", description="Resolution % of both renders (0: the scene's)", default=0, min=0, max=100
    )

    @classmethod
    def poll(cls, context):
        return context.scene is not None and context.scene.render.engine == "PENUMBRA"

    def execute(self, context):
        scene = context.scene
        if scene.camera is None:
            self.report({"ERROR"}, "Penumbra: Compare with Cycles needs a scene camera")
            return {"CANCELLED"}
        lights = scene_lights(context)
        if not lights and not _world_emits(scene.world):
            self.report(
                {"ERROR"}, "Penumbra: Compare with Cycles needs light: the scene has no lights and a black world"
            )
            return {"CANCELLED"}
        wm = context.window_manager if context.window is not None else None
        saved = Settings()
        _cancel["requested"] = False
        bpy.app.handlers.render_cancel.append(request_cancel)
        tmp = tempfile.mkdtemp(prefix="penumbra-compare-")
        steps = 4
        if wm is not None:
            wm.progress_begin(0, steps)
        try:
            self._setup(scene, saved)
            images, times = {}, {}
            step = 0
            for engine in ("PENUMBRA", "CYCLES"):
                self._engine(scene, saved, engine)
                for shadows in (True, False):
                    for light in lights:
                        light.data.use_shadow = shadows if light.data in self._shadow_owners else False
                    start = time.perf_counter()
                    bpy.ops.render.render()
                    elapsed = time.perf_counter() - start
                    if _cancel["requested"]:
                        self.report({"WARNING"}, "Penumbra: Compare with Cycles cancelled")
                        return {"CANCELLED"}
                    images[engine, shadows] = self._read_result(scene, tmp, f"{engine}-{shadows}")
                    if shadows:
                        times[engine] = elapsed
                    step += 1
                    if wm is not None:
                        wm.progress_update(step)
            image, numbers = self._build(images, times)
        except Exception as exc:  # a failed render or read: a message, settings restored, no image
            self.report({"ERROR"}, f"Penumbra: Compare with Cycles failed: {exc}")
            return {"CANCELLED"}
        finally:
            saved.restore()
            bpy.app.handlers.render_cancel.remove(request_cancel)
            _cancel["requested"] = False
            for name in os.listdir(tmp):
                os.remove(os.path.join(tmp, name))
            os.rmdir(tmp)
            if wm is not None:
                wm.progress_end()
        self._show(context, image)
        self.report(
            {"INFO"},
            (
                f"Penumbra vs Cycles ({self.samples} samples, Cycles {numbers['cycles_mode'].lower()}): "
                f"shadow IoU {numbers['iou']:.4f}, mean shadow error {numbers['mean_shadow_error']:.4f}, "
                f"mean image error {numbers['mean_image_error']:.4f}; Penumbra {numbers['penumbra_time']:.2f} s, "
                f"Cycles {numbers['cycles_time']:.2f} s"
            ),
        )
        return {"FINISHED"}

    # --- steps ------------------------------------------------------------------------------

    def _setup(self, scene, saved):
        r = scene.render
        saved.record(r, "engine")
        if self.resolution_percentage:
            saved.set(r, "resolution_percentage", self.resolution_percentage)
        # Output format of the temporary files: recorded so that, restored in reverse, the file
        # format comes back before the depth and codec it allows.
        settings = r.image_settings
        for attr in ("exr_codec", "color_depth", "file_format", "media_type"):
            if hasattr(settings, attr):
                saved.record(settings, attr)
        if hasattr(settings, "media_type"):  # Blender 5.x: a media type, then the file format
            settings.media_type = "IMAGE"
        settings.file_format = "OPEN_EXR"
        settings.color_depth = "32"
        settings.exr_codec = "ZIP"
        # Lights whose shadow is on are measured; each light's switch is restored.
        self._shadow_owners = set()
        for ob in scene_lights(bpy.context):
            if ob.data not in self._shadow_owners and ob.data.use_shadow:
                self._shadow_owners.add(ob.data)
            saved.record(ob.data, "use_shadow")

    def _engine(self, scene, saved, engine):
        scene.render.engine = engine
        if engine == "PENUMBRA":
            saved.set(scene.penumbra, "render_samples", self.samples)
            saved.set(scene.penumbra, "debug_view", "NONE")  # the image, not a debug view of it
            # Post layers change the image after the light is computed, where Cycles has none.
            for layer in scene.penumbra.layers:
                if layer.enabled:
                    saved.set(layer, "enabled", False)
            return
        c = scene.cycles
        saved.set(c, "samples", self.samples)
        if self.mode == "DIRECT":
            for attr in (
                "max_bounces",
                "diffuse_bounces",
                "glossy_bounces",
                "transmission_bounces",
                "volume_bounces",
                "transparent_max_bounces",
            ):
                saved.set(c, attr, 0)
            for attr in ("caustics_reflective", "caustics_refractive", "use_denoising", "use_adaptive_sampling"):
                saved.set(c, attr, False)

    def _read_result(self, scene, tmp, name):
        """The last render's Combined pixels (h, w, 4), scene linear, row 0 at the bottom."""
        path = os.path.join(tmp, name + ".exr")
        bpy.data.images["Render Result"].save_render(path, scene=scene)
        image = bpy.data.images.load(path, check_existing=False)
        try:
            w, h = image.size
            pixels = np.empty(w * h * 4, np.float32)
            image.pixels.foreach_get(pixels)
        finally:
            bpy.data.images.remove(image)
        return pixels.reshape(h, w, 4)

    def _build(self, images, times):
        pen, cyc = images["PENUMBRA", True], images["CYCLES", True]
        h, w = pen.shape[:2]
        vis_p = visibility(luminance(pen), luminance(images["PENUMBRA", False]))
        vis_c = visibility(luminance(cyc), luminance(images["CYCLES", False]))
        both = np.isfinite(vis_p) & np.isfinite(vis_c)
        shadow_err = np.abs(vis_p - vis_c)
        lum_p, lum_c = luminance(pen), luminance(cyc)
        level = float(np.percentile(lum_c, 99)) or 1.0
        image_err = np.abs(lum_p - lum_c) / level
        if self.error == "SHADOW":
            err_rgb = colormap(shadow_err)
            err_rgb[~both] = INVALID_COLOR
        else:
            err_rgb = colormap(image_err)
        numbers = {
            "samples": self.samples,
            "cycles_mode": self.mode,
            "error": self.error,
            "iou": shadow_iou(vis_p, vis_c),
            "mean_shadow_error": float(shadow_err[both].mean()) if both.any() else 0.0,
            "mean_image_error": float(image_err.mean()),
            "image_error_scale": level,
            "penumbra_time": times["PENUMBRA"],
            "cycles_time": times["CYCLES"],
        }
        # Below the three parts, under the error part: its colour scale from 0 (left) to 1.
        rows = legend_rows(h)
        numbers["legend_rows"] = rows
        out = np.ones((h + rows, 3 * w, 4), np.float32)
        out[:rows, :, :3] = 0.0
        out[:rows, 2 * w :, :3] = colormap((np.arange(w) + 0.5) / w)[None]
        out[rows:, :w, :3] = pen[..., :3]
        out[rows:, w : 2 * w, :3] = cyc[..., :3]
        out[rows:, 2 * w :, :3] = err_rgb
        old = bpy.data.images.get(IMAGE_NAME)
        if old is not None:
            bpy.data.images.remove(old)
        image = bpy.data.images.new(IMAGE_NAME, 3 * w, h + rows, alpha=True, float_buffer=True)
        try:
            image.pixels.foreach_set(out.ravel())
            image.update()
            for key, value in numbers.items():
                image[key] = value
        except BaseException:
            bpy.data.images.remove(image)
            raise
        return image, numbers

    @staticmethod
    def _show(context, image):
        screen = context.screen
        for area in screen.areas if screen is not None else ():
            if area.type == "IMAGE_EDITOR":
                area.spaces.active.image = image
                return


def legend_rows(height):
    """Rows of the colour scale under a comparison of ``height`` rows (the image's
    ``legend_rows`` property)."""
    return max(4, height // 16)


def menu_entry(self, context):
    if context.scene is not None and context.scene.render.engine == "PENUMBRA":
        self.layout.separator()
        self.layout.operator(PENUMBRA_OT_compare_cycles.bl_idname, icon="IMAGE")


def register():
    bpy.utils.register_class(PENUMBRA_OT_compare_cycles)
    bpy.types.TOPBAR_MT_render.append(menu_entry)


def unregister():
    bpy.types.TOPBAR_MT_render.remove(menu_entry)
    bpy.utils.unregister_class(PENUMBRA_OT_compare_cycles)
