"""The store final renders keep between them (``engine/store.py``): a second F12 of an
unchanged scene extracts no mesh and uploads no vertex data or image, and draws the same
image; an edited mesh is extracted again; the store is emptied on file load and on
unregister, and sheds under memory pressure and beyond its budget. Each case runs in a
child process: the store is the process's."""

import textwrap

from devkit.session import run_result

PRELUDE = """
import json, os, tempfile
import numpy as np
import bpy
from devkit import engines, scenes, session
penumbra = session.load_penumbra()
penumbra.register()
from penumbra.engine import store
from penumbra.engine.frame.renderer import Renderer
from penumbra.engine.scene import extract

EXTRACTED = []
_extract = extract.geometry_from_mesh

def counted(mesh, needs=None):
    EXTRACTED.append(mesh.name)
    return _extract(mesh, needs)

extract.geometry_from_mesh = counted
SEEN = []
_render = Renderer.render

def recorded(self, *args, **kwargs):
    out = _render(self, *args, **kwargs)
    SEEN.append(out.stats)
    return out

Renderer.render = recorded

def f12(scene):
    '''(FrameStats, meshes extracted, Combined as an array) of an F12 render of ``scene``.'''
    EXTRACTED.clear()
    with session.stdout_to_stderr():
        bpy.ops.render.render(write_still=False)
    result = bpy.data.images["Render Result"]
    path = os.path.join(tempfile.mkdtemp(), "f.exr")
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    result.save_render(path)
    from devkit import imageio
    return SEEN[-1], len(EXTRACTED), imageio.read_image(path)

def report(**values):
    print("RESULT " + json.dumps(values))
    session.hard_exit(0)
"""


def run_child(body):
    return run_result(textwrap.dedent(PRELUDE) + textwrap.dedent(body), timeout=300)


def test_a_second_f12_of_an_unchanged_scene_extracts_and_uploads_nothing():
    """The textured asset (UVs, tangents, five images; ``scenes.textured_asset``): the first
    F12 after the store is emptied extracts its mesh and uploads its batches; the second
    extracts nothing, uploads no vertex buffer and no image, and draws the same pixels. A
    moved vertex is extracted again (the store holds no stale mesh) and draws what an empty
    store draws."""
    result, _ = run_child(
        """
        scene = scenes.textured_asset(96, 54)
        engines.configure(scene, "PENUMBRA")
        f12(scene)  # programs compiled, images made
        store.clear()
        cold, cold_n, cold_img = f12(scene)
        warm, warm_n, warm_img = f12(scene)
        mesh = next(o.data for o in scene.objects if o.type == "MESH" and len(o.data.polygons) > 1000)
        mesh.vertices[0].co.z += 0.5
        mesh.update()
        edited, edited_n, edited_img = f12(scene)
        store.clear()
        fresh, fresh_n, fresh_img = f12(scene)
        report(
            cold=[cold_n, cold.mesh_upload_bytes, cold.image_upload_bytes],
            warm=[warm_n, warm.mesh_upload_bytes, warm.image_upload_bytes],
            edited=[edited_n, edited.mesh_upload_bytes],
            same=float(np.abs(cold_img - warm_img).max()),
            edit_fresh=float(np.abs(edited_img - fresh_img).max()),
            moved=float(np.abs(edited_img - warm_img).max()),
            held=store.STORE.held_bytes,
        )
        """
    )
    assert result["cold"][0] >= 1 and result["cold"][1] > 100_000, result
    assert result["cold"][2] == 0  # the images' textures were made by the render before
    assert result["warm"] == [0, 0, 0], result
    assert result["same"] == 0.0  # bit for bit
    assert result["edited"][0] >= 1 and result["edited"][1] > 0, result
    assert result["edit_fresh"] == 0.0
    assert result["moved"] > 0.0  # the vertex moved in the image (the edit reached the frame)
    assert result["held"] > 100_000


def test_the_store_is_emptied_when_a_file_is_loaded_and_on_unregister():
    result, _ = run_child(
        """
        scene = scenes.textured_asset(48, 27)
        engines.configure(scene, "PENUMBRA")
        f12(scene)
        after_render = len(store.STORE)
        path = os.path.join(tempfile.mkdtemp(), "other.blend")
        bpy.ops.wm.save_as_mainfile(filepath=path)
        bpy.ops.wm.open_mainfile(filepath=path)
        after_load = len(store.STORE)
        scene = bpy.context.scene
        f12(scene)
        again = len(store.STORE)
        penumbra.unregister()
        after_unregister = len(store.STORE)
        handlers = [h for h in bpy.app.handlers.load_pre if getattr(h, "__module__", "").startswith("penumbra")]
        report(
            after_render=after_render,
            after_load=after_load,
            again=again,
            after_unregister=after_unregister,
            handlers=len(handlers),
        )
        """
    )
    assert result["after_render"] >= 2  # the geometry and its batches at least
    assert result["after_load"] == 0
    assert result["again"] >= 2
    assert result["after_unregister"] == 0 and result["handlers"] == 0


def test_the_store_sheds_under_memory_pressure_and_stays_within_its_budget():
    """With the system's available memory reported under ``store.LOW_MEMORY`` of its total,
    the next final render first sheds the older half of the store; with a budget smaller than
    a frame's meshes, the store holds at most its budget and the images are unchanged."""
    result, _ = run_child(
        """
        scene = scenes.textured_asset(48, 27)
        engines.configure(scene, "PENUMBRA")
        _, _, full = f12(scene)
        held = store.STORE.held_bytes
        store.STORE.memory = lambda: (1, 100)
        dropped = store.STORE.dropped
        f12(scene)  # sheds first, then keeps what this frame made again
        shed = store.STORE.dropped - dropped
        store.STORE.memory = store.available_memory
        store.clear()
        store.STORE.budget = held // 4
        _, _, small = f12(scene)
        report(
            held=held,
            shed=shed,
            budget=store.STORE.budget,
            small_held=store.STORE.held_bytes,
            same=float(np.abs(full - small).max()),
            probe=list(store.available_memory() or (0, 0)),
        )
        """
    )
    assert result["shed"] >= 1
    assert 0 < result["small_held"] <= result["budget"]
    assert result["same"] == 0.0
    available, total = result["probe"]
    assert 0 < available <= total  # the probe reads this system's memory (Linux)


def test_a_second_f12_under_the_same_hdri_prefilters_nothing():
    """A world's Environment Texture (a real outdoor HDRI, ``reflection_scenes.hdri_spheres``):
    the first F12 after the store is emptied prefilters it, the second takes the atlas from
    the store and draws the same pixels; after its pixels change (``Image.pixels``, then
    ``update``) it is prefiltered again and draws what an empty store draws."""
    result, _ = run_child(
        """
        from devkit import reflection_scenes
        from penumbra.engine.frame.features import world_env
        BUILT = []
        _build = world_env.prefilter_environment

        def counting(*args, **kwargs):
            BUILT.append(1)
            return _build(*args, **kwargs)

        world_env.prefilter_environment = counting
        scene = reflection_scenes.build("hdri_spheres", 48, 27)
        engines.configure(scene, "PENUMBRA")
        scene.penumbra.render_samples = 1
        f12(scene)
        store.clear()
        BUILT.clear()
        _, _, cold = f12(scene)
        cold_built = len(BUILT)
        _, _, warm = f12(scene)
        warm_built = len(BUILT) - cold_built
        image = next(i for i in bpy.data.images if i.source == "FILE")
        pixels = np.empty(len(image.pixels), np.float32)
        image.pixels.foreach_get(pixels)
        pixels[0::4] *= 0.25  # the red channel quartered: another sky
        image.pixels.foreach_set(pixels)
        image.update()
        BUILT.clear()
        _, _, edited = f12(scene)
        edited_built = len(BUILT)
        store.clear()
        _, _, fresh = f12(scene)
        report(
            cold_built=cold_built,
            warm_built=warm_built,
            edited_built=edited_built,
            same=float(np.abs(cold - warm).max()),
            edit_fresh=float(np.abs(edited - fresh).max()),
            changed=float(np.abs(edited - warm).max()),
        )
        """
    )
    assert result["cold_built"] == 1 and result["warm_built"] == 0, result
    assert result["same"] == 0.0
    assert result["edited_built"] == 1 and result["edit_fresh"] == 0.0, result
    assert result["changed"] > 0.01  # the edit reached the frame


def test_the_textured_asset_is_built_in_one_order_in_every_process():
    """Blender's UV sphere operator orders its faces differently in every process, so the
    asset built with it rasterised differently to the last bit from run to run (up to 0.007
    at the sun's soft shadow edge), which hid whether a change to the engine moved a pixel.
    ``scenes.uv_sphere`` builds it in one order: two processes make the same corners and UV
    map, and its UV map is Blender's layout (u around, the seam at u = 1: no face spans it)."""
    body = """
    import hashlib
    scene = scenes.textured_asset(16, 9, texels=8)
    me = bpy.data.objects["Sphere"].data
    corners = np.zeros(len(me.loops), np.int32)
    me.loops.foreach_get("vertex_index", corners)
    uv = np.zeros(2 * len(me.loops), np.float32)
    me.uv_layers["UVMap"].data.foreach_get("uv", uv)
    uv = uv.reshape(-1, 2)
    span = max(float(np.ptp(uv[list(p.loop_indices), 0])) for p in me.polygons)
    digest = hashlib.md5(corners.tobytes() + uv.tobytes()).hexdigest()
    report(digest=digest, span=span, faces=len(me.polygons), u=[float(uv[:, 0].min()), float(uv[:, 0].max())])
    """
    first, _ = run_child(body)
    second, _ = run_child(body)
    assert first["digest"] == second["digest"]
    assert first["faces"] == 128 * 64  # 128 segments, 64 rings: quads and the poles' triangles
    assert first["span"] <= 1.0 / 128 + 1e-6  # no face wraps around the seam
    assert first["u"] == [0.0, 1.0]
