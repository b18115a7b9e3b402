"""Final renders write exactly the pixels Blender asks for: the render region (cropped or
not), Blender's integer resolution rule, every view layer into its own layer, every eye of a
stereo render, a transparent film. Every render runs in a child process, so a crash (a render
region with crop once segfaulted Blender) fails the test instead of the run."""

import subprocess
import sys
import textwrap

import bpy
import pytest

from devkit.session import ROOT, run_result

PRELUDE = """
import json, os, tempfile
import numpy as np
import bpy
from devkit import imageio, scenes, session
session.load_penumbra().register()
TMP = tempfile.mkdtemp()

def render_layers(scene, name="frame"):
    '''Render through Blender's output path; {(layer, view): {pass: array}}, row 0 at the bottom.'''
    imageio.set_format(scene.render.image_settings, "OPEN_EXR_MULTILAYER", color_depth="32", exr_codec="ZIP")
    if scene.render.use_multiview:
        scene.render.image_settings.views_format = "MULTIVIEW"
    path = os.path.join(TMP, name + ".exr")
    scene.render.filepath = path
    scene.render.use_file_extension = False
    bpy.ops.render.render(write_still=True)
    return {k: {p: a[::-1] for p, a in v.items()} for k, v in imageio.read_exr_layers(path).items()}

def combined(scene, name="frame"):
    (only,) = render_layers(scene, name).values()
    return only["Combined"]

def demo(width, height):
    scene = scenes.demo_scene(width, height)
    scene.view_layers[0].name = "ViewLayer"
    return scene

def report(**values):
    print("RESULT " + json.dumps(values))
    session.hard_exit(0)
"""


def run_child(body):
    return run_result(textwrap.dedent(PRELUDE) + textwrap.dedent(body), timeout=300)


@pytest.mark.parametrize("crop", [False, True])
def test_render_region_equals_the_same_window_of_a_full_render(crop):
    result, _ = run_child(
        f"""
        scene = demo(96, 64)
        full = combined(scene, "full")
        r = scene.render
        r.use_border, r.use_crop_to_border = True, {crop!r}
        r.border_min_x, r.border_max_x, r.border_min_y, r.border_max_y = 0.21, 0.68, 0.13, 0.77
        part = combined(scene, "part")
        # Blender's window: each edge's float32 position truncated to whole pixels.
        f = np.float32
        x0, x1 = int(f(0.21) * f(96)), int(f(0.68) * f(96))
        y0, y1 = int(f(0.13) * f(64)), int(f(0.77) * f(64))
        if {crop!r}:
            window, outside = part, np.zeros(0)
        else:
            window = part[y0:y1, x0:x1]
            mask = np.ones(part.shape[:2], bool)
            mask[y0:y1, x0:x1] = False
            outside = part[mask]
        report(
            shape=list(part.shape), window=[x0, y0, x1, y1],
            max_diff=float(np.abs(window - full[y0:y1, x0:x1]).max()),
            outside_max=float(np.abs(outside).max()) if outside.size else 0.0,
            window_mean=float(window[..., :3].mean()),
        )
        """
    )
    x0, y0, x1, y1 = result["window"]
    expected_shape = [y1 - y0, x1 - x0, 4] if crop else [64, 96, 4]
    assert result["shape"] == expected_shape
    assert result["max_diff"] == 0.0  # bit for bit, post layers included
    assert result["outside_max"] == 0.0  # uncropped: Blender leaves the rest of the frame empty
    assert result["window_mean"] > 0.01


@pytest.mark.parametrize("size,percent", [((200, 100), 29), ((1280, 720), 70), ((100, 100), 29)])
def test_resolution_percentage_follows_blenders_integer_rule(size, percent):
    w, h = size
    result, _ = run_child(
        f"""
        scene = demo({w}, {h})
        scene.penumbra.layers.clear()  # post sizes in pixels would differ between the two sizes
        scene.render.resolution_percentage = {percent}
        scaled = combined(scene, "scaled")
        scene.render.resolution_x, scene.render.resolution_y = {w * percent // 100}, {h * percent // 100}
        scene.render.resolution_percentage = 100
        direct = combined(scene, "direct")
        report(shape=list(scaled.shape), max_diff=float(np.abs(scaled - direct).max()),
               empty_rows=int((np.abs(scaled).sum(axis=(1, 2)) == 0).sum()),
               empty_cols=int((np.abs(scaled).sum(axis=(0, 2)) == 0).sum()))
        """
    )
    assert result["shape"] == [h * percent // 100, w * percent // 100, 4]
    assert result["max_diff"] == 0.0
    assert result["empty_rows"] == 0 and result["empty_cols"] == 0


def test_every_view_layer_gets_its_own_image():
    result, _ = run_child(
        """
        scene = demo(64, 40)
        crate = bpy.data.objects["Crate"]
        props = bpy.data.collections.new("Props")
        scene.collection.children.link(props)
        for c in list(crate.users_collection):
            c.objects.unlink(crate)
        props.objects.link(crate)
        second = scene.view_layers.new("NoProps")
        second.layer_collection.children["Props"].exclude = True
        both = render_layers(scene, "both")
        scene.view_layers["NoProps"].use = False
        first_alone = combined(scene, "first")
        scene.view_layers["NoProps"].use = True
        scene.view_layers["ViewLayer"].use = False
        second_alone = combined(scene, "second")
        a, b = both[("ViewLayer", "")]["Combined"], both[("NoProps", "")]["Combined"]
        report(layers=sorted(k[0] for k in both),
               first=float(np.abs(a - first_alone).max()), second=float(np.abs(b - second_alone).max()),
               differ=float(np.abs(a - b).max()))
        """
    )
    assert result["layers"] == ["NoProps", "ViewLayer"]
    assert result["first"] == 0.0 and result["second"] == 0.0
    assert result["differ"] > 0.05  # the crate is in one layer only


def test_stereo_eyes_differ_and_each_equals_a_mono_render_from_that_eye():
    result, _ = run_child(
        """
        scene = demo(80, 48)
        scene.render.use_multiview = True
        scene.render.views_format = "STEREO_3D"
        cam = scene.camera
        cam.data.stereo.convergence_mode = "OFFAXIS"
        cam.data.stereo.interocular_distance = 0.3
        eyes = {}

        class Probe(bpy.types.RenderEngine):
            '''Blender's own eye matrices and shifts, as a render engine receives them.'''
            bl_idname = "EYE_PROBE"
            bl_label = "Eye probe"

            def render(self, depsgraph):
                for view in ("left", "right"):
                    self.active_view_set(view)
                    c = depsgraph.scene.camera
                    eyes[view] = ([list(r) for r in self.camera_model_matrix(c)], self.camera_shift_x(c))

        bpy.utils.register_class(Probe)
        scene.render.engine = "EYE_PROBE"
        bpy.ops.render.render()
        scene.render.engine = "PENUMBRA"
        stereo = render_layers(scene, "stereo")
        scene.render.use_multiview = False
        from mathutils import Matrix
        diffs = {}
        for view in ("left", "right"):
            matrix, shift = eyes[view]
            cam.matrix_world = Matrix(matrix)
            cam.data.shift_x = shift
            mono = combined(scene, "mono_" + view)
            diffs[view] = float(np.abs(stereo[("ViewLayer", view)]["Combined"] - mono).max())
        left, right = stereo[("ViewLayer", "left")]["Combined"], stereo[("ViewLayer", "right")]["Combined"]
        report(views=sorted(k[1] for k in stereo), diffs=diffs, eyes_differ=float(np.abs(left - right).max()),
               shifts=[eyes["left"][1], eyes["right"][1]])
        """
    )
    assert result["views"] == ["left", "right"]
    assert result["shifts"][0] != result["shifts"][1]  # off-axis: the eyes' frames are shifted
    assert result["eyes_differ"] > 0.05
    # Same pixels up to float rounding of the eye's matrix (the mono camera is set through
    # Blender's float32 object transform).
    assert result["diffs"]["left"] < 1e-3 and result["diffs"]["right"] < 1e-3


def test_transparent_film_leaves_the_background_exactly_zero():
    result, _ = run_child(
        """
        scene = scenes.empty_scene(64, 48)
        scenes.set_world(scene, (0.3, 0.4, 0.5))
        scenes.light(scene, "Sun", "SUN", 3.0)
        scenes.box(scene, center=(0, 0, 0), size=(3, 3, 3))
        scenes.top_camera(scene)
        scene.render.film_transparent = True
        c = combined(scene)
        alpha = c[..., 3]
        background = alpha == 0
        report(bg_fraction=float(background.mean()), bg_max=float(np.abs(c[background]).max()),
               object_alpha=float(alpha[~background].min()))
        """
    )
    assert 0.2 < result["bg_fraction"] < 0.95
    assert result["bg_max"] == 0.0  # RGBA all zero: no world haze when composited
    assert result["object_alpha"] == 1.0


def test_a_frame_larger_than_the_gpu_allows_is_refused_with_a_message():
    result, _ = run_child(
        """
        scene = scenes.empty_scene(64, 48)
        scenes.light(scene, "Sun", "SUN", 3.0)
        scenes.box(scene)
        scenes.top_camera(scene)
        scene.render.resolution_x = 40000  # above every GPU's largest texture (16384 on llvmpipe)
        scene.render.resolution_y = 4
        try:
            bpy.ops.render.render()
            report(error="")
        except RuntimeError as exc:  # the operator's error is the engine's report
            report(error=str(exc))
        """
    )
    assert "Penumbra: 40000x4 is larger than this GPU's largest texture" in result["error"]


def test_post_sizes_in_pixels_follow_the_resolution_percentage():
    """A 50 % preview of a stack with a radius-8 blur and 6-pixel cells is the full-size look
    at half the pixels: the same as a half-size frame with a radius-4 blur and 3-pixel cells."""
    result, _ = run_child(
        """
        scene = demo(200, 120)
        s = scene.penumbra
        s.layers.clear()
        for effect in ("BLUR", "PIXELATE"):
            layer = s.layers.add()
            layer.effect = effect
        s.layers[0].blur.radius, s.layers[1].pixelate.size = 8, 6
        scene.render.resolution_percentage = 50
        preview = combined(scene, "preview")
        scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = 100, 60, 100
        s.layers[0].blur.radius, s.layers[1].pixelate.size = 4, 3
        half = combined(scene, "half")
        s.layers[0].blur.radius, s.layers[1].pixelate.size = 8, 6
        unscaled = combined(scene, "unscaled")
        report(same=float(np.abs(preview - half).max()), unscaled=float(np.abs(preview - unscaled).max()))
        """
    )
    assert result["same"] == 0.0
    assert result["unscaled"] > 0.01  # the sizes really matter in this scene


def test_features_penumbra_does_not_render_are_named_in_the_report():
    result, output = run_child(
        """
        scene = demo(32, 24)
        scene.camera.data.dof.use_dof = True
        scene.camera.data.type = "PANO"
        scene.render.use_motion_blur = True
        layer = scene.view_layers[0]
        layer.use_pass_subsurface_direct = layer.use_pass_subsurface_color = layer.use_pass_ambient_occlusion = True
        layer.use_pass_diffuse_color = layer.use_pass_cryptomatte_object = True  # written
        layer.use_pass_shadow = layer.use_pass_z = layer.use_pass_normal = True  # Depth and Normal are written
        bpy.data.objects["Ball"].is_shadow_catcher = True
        for kind in ("pointclouds", "volumes"):  # object types Penumbra does not draw
            data = getattr(bpy.data, kind).new(kind)
            scene.collection.objects.link(bpy.data.objects.new(kind.title(), data))
        for tree, output in ((bpy.data.materials["Ball"].node_tree, "ShaderNodeOutputMaterial"),
                             (scene.world.node_tree, "ShaderNodeOutputWorld")):  # fmt: skip
            volume = tree.nodes.new("ShaderNodeVolumePrincipled")
            out = next(n for n in tree.nodes if n.bl_idname == output)
            tree.links.new(volume.outputs[0], out.inputs["Volume"])
        area = bpy.data.lights.new("Panel", "AREA")
        area.spread = 0.5
        scene.collection.objects.link(bpy.data.objects.new("Panel", area))
        bpy.ops.render.render()
        report(done=True)
        """
    )
    assert result["done"]
    for message in (
        "panoramic cameras are not rendered (drawn as a perspective camera)",
        "Blender's Subsurface Direct pass is not written",
        "Blender's Subsurface Color pass is not written",
        "Blender's Ambient Occlusion pass is not written",
        "object 'Ball': Shadow Catcher is Cycles-only (drawn as an ordinary object)",
        "area light 'Panel': Spread is not rendered (it emits over the whole half-space)",
        "point cloud object 'Pointclouds' is not drawn",
        "volume object 'Volumes' is not drawn: its OpenVDB grids are not read (a mesh's Volume material is drawn)",
        "object 'Ball': its volume fills its bounding box (the mesh is not a box)",
        "Blender's Shadow pass is not written (switch on Penumbra's own in View Layer > Passes)",
    ):
        assert output.count(f"Penumbra: {message}") == 1, message
    # Drawn (a panoramic camera's depth of field is not: the camera is named as a whole).
    assert "depth of field" not in output and "motion blur" not in output
    assert "Depth pass is not" not in output and "Normal pass is not" not in output and "Z pass" not in output
    assert "Diffuse Color pass" not in output and "Cryptomatte" not in output and "AOV" not in output


def test_final_renders_take_their_textures_from_the_pool_and_draw_every_map_again():
    """A second F12 takes the first one's targets and shadow atlas from the pool
    (``engine/gpu_pool.py``), compiles no program, and gives the image of a render with an empty pool, though the
    pooled atlas still holds the first render's maps (the removed ball's shadow among them).
    Between renders the pool holds no more than its budget."""
    result, _ = run_child(
        """
        from penumbra.engine import gpu_pool
        pool = gpu_pool.FINAL_RENDERS
        scene = demo(96, 64)
        first = combined(scene, "first")
        held, taken = len(pool), pool.taken
        compiled = gpu_pool.final_shaders().compiled
        bpy.data.objects.remove(bpy.data.objects["Ball"])
        second = combined(scene, "second")
        taken = pool.taken - taken
        compiled_again = gpu_pool.final_shaders().compiled - compiled
        pool.clear()
        fresh = combined(scene, "fresh")
        pool.budget = 96 * 64 * 16 * 2  # two RGBA32F targets' worth
        combined(scene, "budget")
        report(
            held=held,
            taken=taken,
            compiled=compiled,
            compiled_again=compiled_again,
            same=float(np.abs(second - fresh).max()),
            changed=float(np.abs(first - second).max()),
            budget_held=pool.held_bytes,
            budget=pool.budget,
        )
        """
    )
    assert result["held"] >= 5 and result["taken"] >= 5  # colour, z-buffer, atlas and two post targets at least
    assert result["compiled"] >= 3 and result["compiled_again"] == 0  # each variant compiles once
    assert result["same"] <= 1e-6
    assert result["changed"] > 0.05  # the ball and its shadow are gone
    assert 0 < result["budget_held"] <= result["budget"]


def test_the_pool_holds_what_the_last_frame_used():
    """Repeated renders of one frame hold one frame's textures (no growth); a large frame's
    targets are released as soon as a small frame follows, and the small frame's textures are
    then exactly what the pool holds, as before the large one (``TexturePool.end_render``)."""
    result, _ = run_child(
        """
        from penumbra.engine import gpu_pool
        pool = gpu_pool.FINAL_RENDERS
        scene = demo(96, 64)

        def held():
            return sorted([w, h, f] for w, h, f, _t in pool._held)

        small = []
        for i in range(3):
            combined(scene, f"small{i}")
            small.append((pool.held_bytes, held()))
        taken = pool.taken
        scene.render.resolution_x, scene.render.resolution_y = 320, 180
        large = []
        for i in range(2):
            combined(scene, f"large{i}")
            large.append((pool.held_bytes, held()))
        scene.render.resolution_x, scene.render.resolution_y = 96, 64
        combined(scene, "small again")
        report(small=small, large=large, again=[pool.held_bytes, held()], taken=taken)
        """
    )
    small, large, again = result["small"], result["large"], result["again"]
    assert small[0] == small[1] == small[2]  # equal frames: one frame's textures, no growth
    assert large[0] == large[1]
    assert result["taken"] >= 2 * 5  # the second and third small renders took their targets from the pool
    assert any(w == 320 and h == 180 for w, h, _f in large[1][1])  # the large frame's targets were held
    assert not any(w == 320 and h == 180 for w, h, _f in again[1])  # ... and are gone after a small frame
    assert again == list(small[2])  # what a small frame holds, bytes and textures
    assert small[0][0] < large[0][0]


@pytest.mark.skipif(bpy.app.version < (5, 0, 0), reason="bpy 4.5 as a module can hang in its own exit after GPU work")
def test_pooled_textures_are_freed_before_blender_exits():
    """Renders leave textures in the pool, and the interpreter still exits normally (no hard
    exit): exit status 0, nothing reported unfreed."""
    script = textwrap.dedent(PRELUDE) + textwrap.dedent(
        """
        scene = demo(48, 32)
        combined(scene, "a")
        combined(scene, "b")
        from penumbra.engine import gpu_pool
        print("POOLED", len(gpu_pool.FINAL_RENDERS))
        """
    )
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300, cwd=ROOT)
    out = proc.stdout + proc.stderr
    assert proc.returncode == 0, out[-3000:]
    pooled = int(next(ln for ln in proc.stdout.splitlines() if ln.startswith("POOLED ")).split()[1])
    assert pooled >= 3
    assert "Not freed memory blocks" not in out and "Traceback" not in out, out[-3000:]


def test_the_report_says_the_samples_a_frame_stopped_at():
    """A frame that stops early says so in the render report: every pixel converged (only hard
    lights, no pixel filter: all samples alike), or its time limit passed."""
    result, output = run_child(
        """
        scene = scenes.empty_scene(24, 24)
        scene.view_layers[0].name = "ViewLayer"
        scenes.box_over_plane(scene)
        scenes.light(scene, "Sun", "SUN", 3.0, rotation=(0.3, 0.2, 0), angle=0.0)
        scenes.top_camera(scene)
        p = scene.penumbra
        p.filter_size, p.render_samples, p.adaptive_min_samples = 0.0, 64, 8
        p.shadow_map_jitter = False  # and no map jitter: every sample the same image
        bpy.ops.render.render()
        scene.objects["Sun"].data.angle = 0.2  # soft: pixels keep sampling, until the limit
        p.use_adaptive_sampling, p.render_samples, p.time_limit = False, 4096, 0.3
        bpy.ops.render.render()
        report(done=True)
        """
    )
    assert result["done"]
    assert "Penumbra: ViewLayer: Sample 8/64 | Noise Threshold reached" in output
    assert "Time Limit reached" in output and "Sample 4096/4096" not in output
