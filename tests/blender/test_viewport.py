"""The viewport path (camera from a RegionView3D's matrices, display through Blender's colour
management) gives the same pixels as the final render."""

import math

import numpy as np
import pytest

from devkit import scenes
from devkit.render import render


def _viewport_frame(gpu_call, scene):
    """Run the engine's viewport code path on the scene camera's matrices, inside a GPU context.

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
                engine.draw_display(scene, out.color, w, h)
            from penumbra.engine.renderer import buffer_array

            display = buffer_array(fb.read_color(0, 0, w, h, 4, 0, "FLOAT")).reshape(h, w, 4).copy()
        offscreen.free()
        return linear, display

    return gpu_call(job)


@pytest.mark.parametrize(
    "stack", ["demo", "every effect", "normal map", "environment world", "alpha", "colour attribute"]
)
def test_viewport_matches_final_render(penumbra, gpu_call, stack):
    from devkit import material_scenes

    builders = {
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

    from penumbra.engine.extract import camera_from_view
    from penumbra.engine.lightspace import orthographic, perspective

    view = Matrix.Translation((1.0, -2.0, -10.0))
    persp = camera_from_view(view, Matrix(perspective(math.radians(50), 1.5, 0.1, 100).tolist()))
    ortho = camera_from_view(view, Matrix(orthographic(-4, 4, -3, 3, 0.1, 100).tolist()))
    assert not persp.is_ortho and ortho.is_ortho
    np.testing.assert_allclose(persp.position, (-1.0, 2.0, 10.0), atol=1e-6)
