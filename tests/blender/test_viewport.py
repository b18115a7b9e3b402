"""The viewport path (camera from a RegionView3D's matrices, display through Blender's colour
management) gives the same pixels as the final render."""

import math

import numpy as np
import pytest

from devkit import scenes
from devkit.render import render


def _viewport_frame(gpu_call, scene, window=None, frame=None):
    """Run the engine's viewport code path on the scene camera's matrices, inside a GPU context.
    ``window``: a render region's ``output.Window``, given to ``draw_display``; ``frame``: a
    list that receives the window ``viewport_region`` finds in camera view.

    Returns (scene-linear pixels, display pixels after ``draw_display``), rows bottom-up."""

    def job(engine, depsgraph):
        import gpu
        from mathutils import Matrix

        r = scene.render
        w, h = r.resolution_x, r.resolution_y
        cam = scene.camera.evaluated_get(depsgraph)
        # What a RegionView3D reports in camera view when the camera frame fills the region.
        view_matrix = cam.matrix_world.inverted()
        window_matrix = cam.calc_matrix_camera(depsgraph, x=w, y=h, scale_x=1.0, scale_y=1.0)
        out, _rendered = engine.viewport_frame(depsgraph, view_matrix, window_matrix, w, h)  # what view_draw runs
        if frame is not None:
            # The window view_draw takes from the region's own data (RegionView3D, SpaceView3D).
            from types import SimpleNamespace

            rv3d = SimpleNamespace(view_perspective="CAMERA", perspective_matrix=window_matrix @ view_matrix)
            context = SimpleNamespace(region_data=rv3d, space_data=None)
            frame.append(engine.viewport_region(context, depsgraph, w, h))
        linear = out.color_array().copy()
        offscreen = gpu.types.GPUOffScreen(w, h, format="RGBA32F")
        with offscreen.bind():
            fb = gpu.state.active_framebuffer_get()
            fb.clear(color=(0.0, 0.0, 0.0, 0.0))
            with gpu.matrix.push_pop(), gpu.matrix.push_pop_projection():
                # Region pixel space, as Blender sets it up before calling view_draw.
                gpu.matrix.load_identity()
                proj = Matrix(((2 / w, 0, 0, -1), (0, 2 / h, 0, -1), (0, 0, -1, 0), (0, 0, 0, 1)))
                gpu.matrix.load_projection_matrix(proj)
                engine.draw_display(scene, out.color, w, h, window)
            from penumbra.engine.frame.film import buffer_array

            display = buffer_array(fb.read_color(0, 0, w, h, 4, 0, "FLOAT")).reshape(h, w, 4).copy()
        offscreen.free()
        return linear, display

    return gpu_call(job)


@pytest.mark.parametrize(
    "stack",
    ["demo", "every effect", "normal map", "environment world", "alpha", "colour attribute", "compiled node tree"],
)
def test_viewport_matches_final_render(penumbra, gpu_call, stack):
    from devkit import material_scenes, node_scenes

    builders = {
        "compiled node tree": node_scenes.compiled_sphere,
        "normal map": material_scenes.normal_map,
        "environment world": material_scenes.world_hdri,
        "alpha": material_scenes.alpha_quarter,
        "colour attribute": material_scenes.color_attribute,
    }
    scene = builders[stack](64, 64) if stack in builders else scenes.demo_scene(160, 90)
    if stack == "every effect":
        from penumbra.engine.post import EFFECTS

        for eid in EFFECTS:
            layer = scene.penumbra.layers.add()
            layer.effect, layer.mix = eid, 0.5
        scene.frame_set(7)  # animated layers read the frame in both paths
    scene.view_settings.view_transform = "AgX"
    scene.view_settings.exposure = 0.5
    final = render(scene)["Combined"]
    linear, display = _viewport_frame(gpu_call, scene)
    # Same renderer, same camera: scene-linear pixels agree to float precision.
    np.testing.assert_allclose(linear, final, rtol=1e-5, atol=1e-6)
    assert final[..., :3].max() > 0.1  # not a black frame
    # What the viewport receives is that same scene-linear frame: since Blender 2.91 the
    # display-space shader is a pass-through and the viewport applies the scene's view
    # transform, look and exposure when it composites, exactly as for the saved render.
    np.testing.assert_allclose(display, linear, rtol=1e-5, atol=1e-5)


def test_viewport_camera_from_region_matrices(penumbra):
    """``camera_from_view`` detects orthographic views and inverts the view matrix correctly."""
    from mathutils import Matrix

    from penumbra.engine.scene.extract import camera_from_view
    from penumbra.engine.shadows.lightspace import orthographic, perspective

    view = Matrix.Translation((1.0, -2.0, -10.0))
    persp = camera_from_view(view, Matrix(perspective(math.radians(50), 1.5, 0.1, 100).tolist()))
    ortho = camera_from_view(view, Matrix(orthographic(-4, 4, -3, 3, 0.1, 100).tolist()))
    assert not persp.is_ortho and ortho.is_ortho
    np.testing.assert_allclose(persp.position, (-1.0, 2.0, 10.0), atol=1e-6)


def test_a_render_region_shows_only_its_window_in_the_viewport(penumbra, gpu_call):
    """In camera view the scene's Render Region is a fraction of the camera frame (found in
    region pixels from the camera's frame corners); only its pixels are drawn, the same ones
    as without it, as Blender's engines show it."""
    scene = scenes.demo_scene(96, 64)
    r = scene.render
    r.use_border = True
    r.border_min_x, r.border_max_x, r.border_min_y, r.border_max_y = 0.25, 0.75, 0.1, 0.6
    found = []
    _full_linear, full = _viewport_frame(gpu_call, scene, frame=found)
    window = found[0]  # the camera frame fills the region here: fractions of 96 x 64
    assert (window.x0, window.y0, window.x1, window.y1) == (24, 6, 72, 38)
    _linear, shown = _viewport_frame(gpu_call, scene, window=window)
    inside = np.zeros((64, 96), bool)
    inside[6:38, 24:72] = True
    np.testing.assert_allclose(shown[inside], full[inside], atol=1e-6)
    assert not shown[~inside].any() and full[~inside][..., 3].min() > 0.5


def test_viewport_window_rules():
    from penumbra.engine.frame.output import viewport_window

    assert viewport_window(100, 50, False, (0.2, 0.2, 0.4, 0.4)) == viewport_window(100, 50, True, (0, 0, 1, 1))
    # The viewport's own region: fractions of the region.
    w = viewport_window(100, 50, True, (0.2, 0.1, 0.5, 0.9))
    assert (w.x0, w.y0, w.x1, w.y1) == (20, 5, 50, 45)
    # Camera view: fractions of the camera frame, clamped to the region; empty when outside.
    w = viewport_window(100, 50, True, (0.5, 0.0, 1.0, 1.0), frame=(40.0, -10.0, 140.0, 60.0))
    assert (w.x0, w.y0, w.x1, w.y1) == (90, 0, 100, 50)
    assert viewport_window(100, 50, True, (0.5, 0.0, 1.0, 1.0), frame=(200.0, 0.0, 300.0, 50.0)) is None


def test_outside_camera_view_the_viewports_own_render_region_counts(penumbra):
    """Away from the camera, the viewport's own Render Region (Ctrl+B; fractions of the
    region) decides, whatever the scene's; in camera view the scene's does."""
    from types import SimpleNamespace

    import bpy

    from penumbra.engine.render_engine import PenumbraEngineCore

    scene = scenes.demo_scene(96, 64)
    scene.render.use_border = False
    space = SimpleNamespace(
        use_render_border=True,
        render_border_min_x=0.5,
        render_border_min_y=0.0,
        render_border_max_x=1.0,
        render_border_max_y=0.5,
    )
    context = SimpleNamespace(region_data=SimpleNamespace(view_perspective="PERSP"), space_data=space)
    window = PenumbraEngineCore.viewport_region(None, context, SimpleNamespace(scene=scene), 200, 100)
    assert (window.x0, window.y0, window.x1, window.y1) == (100, 0, 200, 50)
    space.use_render_border = False
    window = PenumbraEngineCore.viewport_region(None, context, SimpleNamespace(scene=bpy.context.scene), 200, 100)
    assert (window.x0, window.y0, window.x1, window.y1) == (0, 0, 200, 100)
