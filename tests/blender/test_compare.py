"""Compare with Cycles (``penumbra.compare_cycles``), called from Python without a window as a
batch script would: a box over a plane under a sharp sun agrees with Cycles, every setting it
touched comes back, a cancel leaves nothing behind, and a scene it cannot compare gets a clear
message. The renders run in child processes, so a crash fails a test instead of the run."""

import textwrap

import bpy
import pytest

from devkit import scenes
from devkit.session import run_result

PRELUDE = """
import json, math
import numpy as np
import bpy
from devkit import scenes, session
session.load_penumbra().register()
from penumbra.operators import compare

def box_scene():
    '''96x64, an orthographic camera looking down on a unit box 1 m over a plane, a sun of
    0.5 deg 30 deg off the vertical: the whole shadow in frame.'''
    scene = scenes.empty_scene(96, 64)
    scenes.box_over_plane(scene, box_center=(-0.6, 0.6, 1.0))
    scenes.light(scene, "Sun", "SUN", 3.0, rotation=(math.radians(-30), 0, math.radians(30)), angle=math.radians(0.5))
    scenes.top_camera(scene, height=10.0, ortho_scale=4.0)
    return scene

def touched(scene):
    '''Every setting the compare may change, as plain values.'''
    c, r, s = scene.cycles, scene.render, scene.render.image_settings
    names = ("samples", "max_bounces", "diffuse_bounces", "glossy_bounces", "transmission_bounces",
             "volume_bounces", "transparent_max_bounces", "caustics_reflective", "caustics_refractive",
             "use_denoising", "use_adaptive_sampling", "device", "seed")
    values = {"cycles." + n: getattr(c, n) for n in names}
    values.update({"render." + n: getattr(r, n) for n in ("engine", "resolution_percentage", "filepath")})
    values.update({"format." + n: getattr(s, n) for n in ("file_format", "color_depth", "exr_codec", "media_type")
                   if hasattr(s, n)})
    values["penumbra.render_samples"] = scene.penumbra.render_samples
    values["penumbra.use_adaptive_sampling"] = scene.penumbra.use_adaptive_sampling
    values["penumbra.debug_view"] = scene.penumbra.debug_view
    values["penumbra.layers"] = [(layer.effect, layer.enabled) for layer in scene.penumbra.layers]
    values.update({"light." + ob.name: ob.data.use_shadow for ob in scene.objects if ob.type == "LIGHT"})
    values["passes"] = [scene.view_layers[0].use_pass_z, scene.view_layers[0].penumbra.use_pass_shadow]
    return values

def unusual(scene):
    '''Settings away from what the compare sets, so a restore that forgot one shows.'''
    c = scene.cycles
    c.samples, c.max_bounces, c.diffuse_bounces, c.glossy_bounces = 7, 5, 3, 2
    c.use_denoising, c.use_adaptive_sampling = True, True
    c.caustics_reflective = c.caustics_refractive = True
    scene.penumbra.render_samples = 3
    # A debug view and a post layer: the compare shows the image without either.
    scene.penumbra.debug_view = "LIGHT_COST"
    scene.penumbra.layers.clear()
    scene.penumbra.layers.add().effect = "VIGNETTE"
    scene.render.image_settings.file_format = "PNG"
    scene.render.image_settings.color_depth = "16"

def parts(image):
    w, h = image.size
    px = np.empty(w * h * 4, np.float32)
    image.pixels.foreach_get(px)
    px = px.reshape(h, w, 4)
    rows = image["legend_rows"]
    third = w // 3
    # The error part's colour scale runs under it, 0 to 1 from left to right.
    legend = px[:rows, 2 * third:, :3]
    assert np.allclose(legend, compare.colormap((np.arange(third) + 0.5) / third)[None], atol=1e-5)
    px = px[rows:]
    return px[:, :third], px[:, third:2 * third], px[:, 2 * third:]

def report(**values):
    print("RESULT " + json.dumps(values))
    session.hard_exit(0)
"""


def run_child(body):
    return run_result(textwrap.dedent(PRELUDE) + textwrap.dedent(body), timeout=120)


def test_box_over_plane_agrees_with_cycles_and_every_setting_comes_back():
    result, log = run_child(
        """
        scene = box_scene()
        unusual(scene)
        before = touched(scene)
        status = bpy.ops.penumbra.compare_cycles(samples=16)
        after = touched(scene)
        image = bpy.data.images[compare.IMAGE_NAME]
        pen, cyc, err = parts(image)
        # The error part back to error values: the nearest entry of a fine table of the map.
        table = compare.colormap(np.linspace(0.0, 1.0, 256))
        dist = ((err[..., None, :3] - table[None, None]) ** 2).sum(-1)
        value = dist.argmin(-1) / 255.0
        # Away from edges: more than 2 px from any pixel whose Cycles luminance steps by > 0.05.
        lum = compare.luminance(cyc)
        edge = np.zeros(lum.shape, bool)
        edge[:, 1:] |= np.abs(np.diff(lum, axis=1)) > 0.05
        edge[:, :-1] |= np.abs(np.diff(lum, axis=1)) > 0.05
        edge[1:] |= np.abs(np.diff(lum, axis=0)) > 0.05
        edge[:-1] |= np.abs(np.diff(lum, axis=0)) > 0.05
        near = edge.copy()
        for dy in range(-2, 3):
            for dx in range(-2, 3):
                near |= np.roll(np.roll(edge, dy, 0), dx, 1)
        numbers, size = {k: image[k] for k in image.keys()}, list(image.size)
        full = bpy.ops.penumbra.compare_cycles(samples=16, mode="FULL", error="SHADOW")
        report(
            status=sorted(status), full=sorted(full), restored=before == after,
            before=before, after=after, size=size, numbers=numbers,
            full_mode=bpy.data.images[compare.IMAGE_NAME]["cycles_mode"],
            images=[im.name for im in bpy.data.images if im.name.startswith("Penumbra vs")],
            away_max=float(value[~near].max()), away_pixels=int((~near).sum()),
            pen_cyc_away=float(np.abs(compare.luminance(pen) - lum)[~near].max()),
        )
        """
    )
    n = result["numbers"]
    print(
        {k: n[k] for k in ("iou", "mean_shadow_error", "mean_image_error", "penumbra_time", "cycles_time")},
        result["away_max"],
        result["pen_cyc_away"],
        result["away_pixels"],
    )
    assert result["status"] == ["FINISHED"] and result["full"] == ["FINISHED"]
    assert result["size"] == [3 * 96, 64 + result["numbers"]["legend_rows"]]
    # 16 samples of each: the shadow's edge pixels straddle the 0.5 line in Cycles' own noise
    # (0.959 with the gathering film, whose edges are smoother than Cycles' 16 spp).
    assert n["iou"] >= 0.95
    assert n["mean_shadow_error"] < 0.02 and n["mean_image_error"] < 0.02
    assert n["penumbra_time"] > 0 and n["cycles_time"] > 0 and n["samples"] == 16
    assert "shadow IoU" in log  # the report
    # Away from edges the two renders agree to 5% of white and the error image shows < 0.05.
    assert result["away_pixels"] > 0.5 * 96 * 64
    assert result["pen_cyc_away"] < 0.05
    assert result["away_max"] < 0.05
    assert result["restored"], (result["before"], result["after"])
    assert result["full_mode"] == "FULL"
    assert result["images"] == ["Penumbra vs Cycles"]  # a second compare replaces the first image


def test_cancel_leaves_no_image_and_restores_settings():
    result, log = run_child(
        """
        scene = box_scene()
        unusual(scene)
        before = touched(scene)
        images = sorted(im.name for im in bpy.data.images)
        renders = []

        def after_render(*_args):
            renders.append(scene.render.engine)
            compare.request_cancel()  # what Esc during a render does, through render_cancel

        bpy.app.handlers.render_post.append(after_render)
        status = bpy.ops.penumbra.compare_cycles(samples=16)
        bpy.app.handlers.render_post.remove(after_render)
        report(
            status=sorted(status), renders=renders, restored=before == touched(scene),
            new_images=sorted(set(im.name for im in bpy.data.images) - set(images) - {"Render Result"}),
            handlers=[h.__name__ for h in bpy.app.handlers.render_cancel],
        )
        """
    )
    assert result["status"] == ["CANCELLED"]
    assert result["renders"] == ["PENUMBRA"]  # it stopped after the first render
    assert result["new_images"] == []
    assert result["restored"]
    assert result["handlers"] == []
    assert "Compare with Cycles cancelled" in log


def test_a_scene_without_camera_or_light_gets_a_clear_message(penumbra):
    scene = scenes.empty_scene(32, 32)
    scenes.box_over_plane(scene)
    scenes.light(scene, "Sun", "SUN", 3.0)
    with pytest.raises(RuntimeError, match="Compare with Cycles needs a scene camera"):
        bpy.ops.penumbra.compare_cycles(samples=1)
    scenes.top_camera(scene)
    bpy.data.objects.remove(bpy.data.objects["Sun"])
    with pytest.raises(RuntimeError, match="needs light: the scene has no lights and a black world"):
        bpy.ops.penumbra.compare_cycles(samples=1)
    assert "Penumbra vs Cycles" not in bpy.data.images


def test_the_render_menu_and_sampling_panel_offer_it_only_for_penumbra(penumbra):
    from penumbra.operators import compare
    from penumbra.ui import panels

    assert compare.menu_entry in bpy.types.TOPBAR_MT_render._dyn_ui_initialize()
    assert panels.PENUMBRA_PT_sampling.draw is not panels._SettingsPanel.draw  # it adds the button
    scene = scenes.empty_scene(32, 32)
    assert bpy.ops.penumbra.compare_cycles.poll()
    scene.render.engine = "CYCLES"
    assert not bpy.ops.penumbra.compare_cycles.poll()
