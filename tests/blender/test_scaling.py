"""A frame costs what the scene needs: what must not happen, counted rather than timed
(instances extracted once, no re-render for a redraw with nothing changed, a variant without
shadow code when no light has a map)."""

import math

import bpy
import numpy as np

from devkit import scenes
from devkit.render import engine_frame


def _instanced_scene(count):
    """``count`` collection instances of one bunny-sized mesh (a UV sphere) over a ground, lit
    by a sun."""
    scene = scenes.empty_scene(96, 54)
    mat = scenes.white()
    scenes.plane(scene, "Ground", size=20.0, mat=mat)
    source = bpy.data.collections.new("Source")
    scene.collection.children.link(source)
    ball = scenes.uv_sphere(scene, "Ball", radius=0.4, mat=mat)
    scene.collection.objects.unlink(ball)
    source.objects.link(ball)
    scene.view_layers[0].layer_collection.children["Source"].exclude = True  # drawn only as instances
    for i in range(count):
        empty = bpy.data.objects.new(f"Instance{i}", None)
        empty.instance_type = "COLLECTION"
        empty.instance_collection = source
        empty.location = ((i % 4) * 1.5 - 2.25, (i // 4) * 1.5 - 2.25, 0.6)
        scene.collection.objects.link(empty)
    scenes.light(scene, "Sun", "SUN", 3.0, rotation=(math.radians(30), 0, math.radians(20)))
    scenes.look_at(scene, (0, -9, 7), (0, 0, 0))
    return scene


def test_collection_instances_share_one_extracted_geometry(penumbra, gpu_call):
    scene = _instanced_scene(16)

    def job(engine, depsgraph):
        from penumbra.engine.scene.extract import camera_from_scene

        out = engine.render_frame(depsgraph, camera_from_scene(depsgraph, scene, 96, 54), 96, 54)
        keys = {inst.key for inst in engine.cache.snapshot(depsgraph).instances}
        return engine.cache.built, len(keys), out.stats.draws, out.color_array().copy()

    built, keys, draws, image = gpu_call(job)
    assert keys == 2 and built == 2  # the ground and the one sphere mesh, for 17 drawn instances
    assert draws >= 17
    # Every instance is drawn where it stands: 16 distinct sphere silhouettes, not one.
    assert (image[..., :3].sum(axis=-1) > 0).mean() > 0.3


def test_instances_of_a_modified_object_share_its_evaluated_geometry(penumbra, gpu_call):
    scene = _instanced_scene(4)
    ball = bpy.data.objects["Ball"]
    ball.modifiers.new("Bevel", "BEVEL")  # an evaluated mesh of its own, shared by the instances

    def job(engine, depsgraph):
        from penumbra.engine.scene.extract import camera_from_scene

        engine.render_frame(depsgraph, camera_from_scene(depsgraph, scene, 96, 54), 96, 54)
        return engine.cache.built

    assert gpu_call(job) == 2


def test_geometry_nodes_instances_of_different_meshes_stay_distinct(penumbra, gpu_call):
    """Two instance sources on one points object: each keeps its own geometry (a shared key
    would draw one shape at every point)."""
    scene = scenes.empty_scene(96, 54)
    scenes.look_at(scene, (0, -8, 0.01), (0, 0, 0))
    scenes.set_world(scene, (1.0, 1.0, 1.0))
    points = bpy.data.objects.new("Points", bpy.data.meshes.new("Points"))
    points.data.from_pydata([(-2, 0, 0), (2, 0, 0)], [], [])
    scene.collection.objects.link(points)
    tree = bpy.data.node_groups.new("Scatter", "GeometryNodeTree")
    tree.interface.new_socket("Geometry", in_out="INPUT", socket_type="NodeSocketGeometry")
    tree.interface.new_socket("Geometry", in_out="OUTPUT", socket_type="NodeSocketGeometry")
    nodes, links = tree.nodes, tree.links
    group_in, group_out = nodes.new("NodeGroupInput"), nodes.new("NodeGroupOutput")
    join = nodes.new("GeometryNodeJoinGeometry")
    cube, sphere = nodes.new("GeometryNodeMeshCube"), nodes.new("GeometryNodeMeshUVSphere")
    for shape, z in ((cube, 1.5), (sphere, -1.5)):
        place = nodes.new("GeometryNodeInstanceOnPoints")
        move = nodes.new("GeometryNodeTranslateInstances")
        move.inputs["Translation"].default_value = (0, 0, z)
        links.new(group_in.outputs[0], place.inputs["Points"])
        links.new(shape.outputs["Mesh"], place.inputs["Instance"])
        links.new(place.outputs[0], move.inputs["Instances"])
        links.new(move.outputs[0], join.inputs[0])
    links.new(join.outputs[0], group_out.inputs[0])
    points.modifiers.new("Scatter", "NODES").node_group = tree

    def job(engine, depsgraph):

        snap = engine.cache.snapshot(depsgraph)
        return sorted(snap.geometry[i.key].triangle_count for i in snap.instances)

    counts = gpu_call(job)
    cube_tris = 12
    assert counts[:2] == [cube_tris, cube_tris] and counts[2] == counts[3] > cube_tris


def test_viewport_redraw_with_nothing_changed_shows_the_last_frame(penumbra, gpu_call):
    """Nothing changed: the last frame, no render. View moving: a frame at navigation_scale;
    view stopped: the full-resolution frame, then nothing again until something changes."""
    scene = scenes.demo_scene(64, 36)
    scene.penumbra.navigation_scale = 0.5

    def job(engine, depsgraph):
        cam = scene.camera.evaluated_get(depsgraph)
        view = cam.matrix_world.inverted()
        window = cam.calc_matrix_camera(depsgraph, x=64, y=36, scale_x=1.0, scale_y=1.0)
        moved = view.copy()
        moved.translation.x += 0.1
        steps = []

        def redraw(v, width=64, height=36):
            out, rendered = engine.viewport_frame(depsgraph, v, window, width, height)
            steps.append((rendered, out.width, out.height))
            return out

        first = redraw(view)
        image = first.color_array().copy()
        again = redraw(view)
        same = again is first and np.array_equal(again.color_array(), image)
        engine.scene_changed()  # what view_update does on any depsgraph update
        redraw(view)
        redraw(moved)  # navigating: reduced resolution
        redraw(moved)  # the view stopped: refined at full resolution
        redraw(moved)  # nothing changed
        redraw(moved, 64, 40)  # region resized: full resolution at once
        return steps, same

    steps, same = gpu_call(job)
    assert steps == [
        (True, 64, 36),
        (False, 64, 36),
        (True, 64, 36),
        (True, 32, 18),
        (True, 64, 36),
        (False, 64, 36),
        (True, 64, 40),
    ]
    assert same


def test_shadow_atlas_memory_is_what_the_maps_hold(penumbra, gpu_call):
    """FLOAT32 maps are the depth buffer itself (4 bytes a texel, nothing else); FLOAT16 and
    RGBA8 maps add one tile-sized scratch target, not a second atlas-sized buffer."""
    scene = scenes.demo_scene(64, 36)  # a sun and a spot: two tiles in a 2x1 atlas
    scene.penumbra.shadow_map_size = 256
    scene.penumbra.shadow_texels_per_pixel = 0.0  # both at the full size
    tile = 256 * 256
    expected = {"FLOAT32": 2 * tile * 4, "FLOAT16": 2 * tile * 2 + tile * (2 + 4), "RGBA8": 2 * tile * 4 + tile * 8}
    for fmt, bytes_ in expected.items():
        scene.penumbra.shadow_depth_format = fmt
        stats, _image = engine_frame(gpu_call, scene, 64, 36)
        assert stats.shadow_maps == 2
        assert stats.shadow_bytes == bytes_, fmt


def _spot_scene():
    """A ground with boxes, a sun and six spots (one of them pointing at the sky)."""
    scene = scenes.empty_scene(160, 90)
    mat = scenes.white()
    scenes.plane(scene, "Ground", size=16.0, mat=mat)
    for i in range(4):
        scenes.box(scene, f"Box{i}", center=(i * 3.0 - 4.5, 0.0, 0.5), mat=mat)
    for i in range(5):
        scenes.light(scene, f"Spot{i}", "SPOT", 300.0, location=(i * 3.0 - 6.0, -1.0, 4.0), spot_size=0.9)
    scenes.light(scene, "SkySpot", "SPOT", 300.0, location=(0.0, 0.0, 4.0), rotation=(math.pi, 0, 0))
    scenes.light(scene, "Sun", "SUN", 1.0, rotation=(math.radians(40), 0, math.radians(30)))
    scenes.look_at(scene, (0.0, -12.0, 9.0), (0.0, 0.0, 0.0))
    return scene


def test_binned_lighting_gives_the_image_of_every_light_on_every_pixel(penumbra, gpu_call, monkeypatch):
    from penumbra.engine.frame import frame_data

    scene = _spot_scene()
    binned_stats, binned = engine_frame(gpu_call, scene, 160, 90)
    assert binned_stats.binned
    monkeypatch.setattr(frame_data, "BIN_MIN_LOCAL_LIGHTS", 10**6)  # every light on every pixel
    stats, full = engine_frame(gpu_call, scene, 160, 90)
    assert not stats.binned
    np.testing.assert_allclose(binned, full, rtol=1e-5, atol=1e-6)
    assert binned[..., :3].max() > 0.2  # the spots do light the ground


def test_a_few_lights_are_called_by_constant_index_with_the_image_of_the_loop(penumbra, gpu_call, monkeypatch):
    """Up to UNROLLED_LIGHTS lights (no bins): the lit variant has the light counts compiled in
    and calls each light by its index. Sun and spot with maps (sampled over their extent in
    four samples, PCSS), a point light without one: the image of the looping variant."""
    from penumbra.engine.frame import programs
    from penumbra.engine.scene.extract import camera_from_scene

    scene = scenes.demo_scene(96, 54)
    scene.penumbra.layers.clear()
    point = scenes.light(scene, "Point", "POINT", 300.0, location=(2.0, -2.0, 3.0))
    scene.penumbra.world_shadows = False  # the world's directions would add suns past UNROLLED_LIGHTS
    point.data.use_shadow = False

    def frames(engine, depsgraph):
        camera = camera_from_scene(depsgraph, scene, 96, 54)
        one = engine.render_frame(depsgraph, camera, 96, 54).color_array().copy()
        four = engine.render_frame(depsgraph, camera, 96, 54, samples=(0, 4), sample_count=4)
        lit = [dict(defines) for name, defines in engine.renderer.shaders._cache if name.startswith("lit")]
        return one, four.color_array().copy(), lit

    one, four, lit = gpu_call(frames)
    counts = {(d["SAMPLED_COUNT"], d["SHADOWED_COUNT"], d["LIGHT_COUNT"]) for d in lit}
    assert lit and all(d["UNROLLED_LIGHTS"] for d in lit)
    assert (0, 2, 3) in counts  # one sample: two lights with maps, one without
    assert any(sampled > 0 for sampled, _mapped, _n in counts)  # four samples: the PCSS calls
    monkeypatch.setattr(programs, "UNROLLED_LIGHTS", 0)
    loop_one, loop_four, loop_lit = gpu_call(frames)
    assert loop_lit and not any(d["UNROLLED_LIGHTS"] for d in loop_lit)
    np.testing.assert_allclose(one, loop_one, rtol=1e-5, atol=1e-6)
    np.testing.assert_allclose(four, loop_four, rtol=1e-5, atol=1e-6)
    assert one[..., :3].max() > 0.2


def test_a_frame_compiles_only_the_programs_it_draws_with(penumbra, gpu_call):
    """Opaque casters and no post layer: one depth program and one lit variant, none of the
    alpha cut-out depth programs; the next frame compiles nothing."""
    from penumbra.engine.scene.extract import camera_from_scene

    scene = scenes.demo_scene(64, 36)
    scene.penumbra.layers.clear()

    def job(engine, depsgraph):
        camera = camera_from_scene(depsgraph, scene, 64, 36)
        first = engine.render_frame(depsgraph, camera, 64, 36).stats.shaders_compiled
        names = sorted(name for name, _defines in engine.renderer.shaders._cache)
        again = engine.render_frame(depsgraph, camera, 64, 36).stats.shaders_compiled
        return first, names, again

    first, names, again = gpu_call(job)
    assert first == len(names) and again == 0
    # The sun's tile is orthographic (rasterised depth), the spot's perspective (gl_FragDepth),
    # both drawn instanced.
    assert [n for n in names if n.startswith("shadow")] == [
        "shadow_depth_only_instanced",
        "shadow_depth_raster_instanced",
    ]
    # One lit variant: the lit program with the parts of the frame's techniques (the demo's
    # world occlusion) and nothing else.
    lit = [n for n in names if n.startswith("lit")]
    assert len(lit) == 1 and lit[0] in ("lit", "lit_ao"), lit


def test_orthographic_tiles_rasterise_the_depth_the_fragment_stage_would_write(penumbra, gpu_call, monkeypatch):
    """A sun's map drawn without gl_FragDepth (its projection is linear in view distance) holds
    the depth the gl_FragDepth program writes, to float precision, and gives the same image;
    an alpha cut-out caster (the cut-out program's raster variant) included."""
    from penumbra.engine.scene.extract import camera_from_scene
    from penumbra.engine.shadows import lightspace

    scene = scenes.demo_scene(96, 54)
    scene.penumbra.layers.clear()
    mat = scenes.material("Cut", (0.6, 0.6, 0.6))
    bsdf = next(n for n in mat.node_tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
    bsdf.inputs["Alpha"].default_value = 0.5
    scenes.plane(scene, "Card", size=1.2, z=1.4, mat=mat).location = (0.8, -0.6, 0.0)

    def job(engine, depsgraph):
        camera = camera_from_scene(depsgraph, scene, 96, 54)
        image = engine.render_frame(depsgraph, camera, 96, 54).color_array().copy()
        atlas = engine.renderer.shadows
        with atlas._framebuffer.bind():
            depth = np.asarray(atlas._framebuffer.read_depth(0, 0, atlas.texture.width, atlas.texture.height))
        names = {name for name, _defines in engine.renderer.shaders._cache}
        return image, depth.astype(np.float32).copy(), names

    image, depth, names = gpu_call(job)
    assert {"shadow_depth_raster_instanced", "shadow_depth_raster_alpha"} <= names
    monkeypatch.setattr(lightspace.Fit, "orthographic", property(lambda self: False))
    ref_image, ref_depth, ref_names = gpu_call(job)
    assert not any("raster" in n for n in ref_names)
    covered = ref_depth < 1.0
    assert covered.mean() > 0.05  # the maps hold casters and receivers
    # Both float32: the rasteriser evaluates the depth plane at the texel, the fragment stage
    # divides the interpolated distance; they differ by a few ulps of the plane (8e-6 measured,
    # a fraction of a millimetre over this tile's range, far below the depth bias).
    np.testing.assert_allclose(depth, ref_depth, rtol=0, atol=2e-5)
    assert np.mean(np.abs(depth - ref_depth) > 1e-6) < 1e-3
    np.testing.assert_allclose(image, ref_image, rtol=1e-5, atol=1e-5)


def test_binned_light_classes_each_get_their_loop(penumbra, gpu_call, monkeypatch):
    """Bins with all three classes of light: soft spots sampled over their extent (four
    samples, PCSS), spots with maps, spots without: the image of every light on every pixel.
    Each class is compiled only when the frame has a light in it. Map jitter is off: with
    it every shadowed light of a frame of several samples is sampled (PCSS class)."""
    from penumbra.engine.frame import frame_data
    from penumbra.engine.scene.extract import camera_from_scene

    scene = _spot_scene()
    scene.penumbra.shadow_map_jitter = False
    bpy.data.lights["Spot0"].shadow_soft_size = 0.5
    bpy.data.lights["Spot1"].shadow_soft_size = 0.5
    bpy.data.lights["Spot3"].use_shadow = False

    def frames(engine, depsgraph):
        camera = camera_from_scene(depsgraph, scene, 160, 90)
        out = engine.render_frame(depsgraph, camera, 160, 90, samples=(0, 4), sample_count=4)
        lit = [dict(d) for name, d in engine.renderer.shaders._cache if name.startswith("lit")]
        return out.stats, out.color_array().copy(), lit

    stats, binned, lit = gpu_call(frames)
    assert stats.binned and stats.lights_sampled >= 1
    assert any(d["LIGHT_BINS"] and d["SAMPLED_LIGHTS"] and d["HAS_SHADOWED"] and d["HAS_UNSHADOWED"] for d in lit)
    monkeypatch.setattr(frame_data, "BIN_MIN_LOCAL_LIGHTS", 10**6)
    full_stats, full, _lit = gpu_call(frames)
    assert not full_stats.binned
    np.testing.assert_allclose(binned, full, rtol=1e-5, atol=1e-6)
    assert binned[..., :3].max() > 0.2

    # Every spot with a map: the variant has no loop for lights without one.
    bpy.data.lights["Spot3"].use_shadow = True
    monkeypatch.setattr(frame_data, "BIN_MIN_LOCAL_LIGHTS", 2)
    _stats, _image, lit = gpu_call(frames)
    assert any(d["LIGHT_BINS"] and not d["HAS_UNSHADOWED"] for d in lit)


def test_a_light_that_reaches_nothing_visible_gets_no_map(penumbra, gpu_call):
    scene = _spot_scene()
    stats, _image = engine_frame(gpu_call, scene, 160, 90)
    assert stats.lights_out_of_view == 1  # the spot pointing at the sky
    assert stats.shadow_maps == 6  # five spots and the sun


def test_maps_hold_the_texels_their_pixels_can_show(penumbra, gpu_call):
    """Five spots and a sun at 160x90 with 2048 maps: sized to the screen (Texels per Pixel
    4) the spots' maps are 256-512 texels wide (the sun's crop, 12 m wide, needs all 2048),
    a fifth of the full-size maps' fill; the five share one atlas slot (a third of the
    memory), and the image is the full-size maps'. At half the resolution every map is half
    as wide."""
    scene = _spot_scene()
    scene.penumbra.shadow_map_size = 2048
    scene.penumbra.shadow_texels_per_pixel = 0.0
    full_stats, full = engine_frame(gpu_call, scene, 160, 90)
    scene.penumbra.shadow_texels_per_pixel = 4.0
    stats, sized = engine_frame(gpu_call, scene, 160, 90)
    assert stats.shadow_maps == full_stats.shadow_maps == 6
    assert full_stats.shadow_texels == 6 * 2048**2
    assert stats.shadow_texels * 4 <= full_stats.shadow_texels
    assert stats.shadow_bytes * 3 <= full_stats.shadow_bytes  # the spots share one slot of the atlas
    lum = lambda img: img[..., :3] @ np.array([0.2126, 0.7152, 0.0722])  # noqa: E731
    assert np.abs(lum(sized) - lum(full)).mean() < 0.01 * lum(full).mean()
    shadowed = lambda img: lum(img) < 0.5 * lum(full).mean()  # noqa: E731
    assert (shadowed(sized) != shadowed(full)).sum() <= 0.01 * shadowed(full).sum() + 4
    half_stats, _half = engine_frame(gpu_call, scene, 80, 45)
    assert 4 * half_stats.shadow_texels == stats.shadow_texels


def test_materials_are_read_once_and_again_only_after_they_change(penumbra):
    """Fifty objects share two materials: two reads, not fifty. Editing one material's node
    value re-reads that material only (the depsgraph update invalidates it), and the next
    snapshot carries the new value."""
    from penumbra.engine.scene.extract import SceneCache

    scene = scenes.empty_scene(32, 32)
    red, blue = scenes.material("Red", (0.8, 0.1, 0.1)), scenes.material("Blue", (0.1, 0.1, 0.8))
    for i in range(50):
        scenes.box(scene, f"Box{i}", center=(i, 0, 0), mat=red if i % 2 else blue)
    cache = SceneCache()

    def on_update(_scene, depsgraph):
        cache.apply_updates(depsgraph)

    cache.snapshot(bpy.context.evaluated_depsgraph_get())
    assert cache.materials_read == 2
    cache.snapshot(bpy.context.evaluated_depsgraph_get())
    assert cache.materials_read == 2  # nothing changed: nothing re-read
    bpy.app.handlers.depsgraph_update_post.append(on_update)
    try:
        bsdf = next(n for n in red.node_tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
        bsdf.inputs["Base Color"].default_value = (0.2, 0.9, 0.3, 1.0)
        snap = cache.snapshot(bpy.context.evaluated_depsgraph_get())
    finally:
        bpy.app.handlers.depsgraph_update_post.remove(on_update)
    assert cache.materials_read == 3
    colours = {tuple(round(c, 3) for c in inst.materials[0].base_color[:3]) for inst in snap.instances}
    assert colours == {(0.2, 0.9, 0.3), (0.1, 0.1, 0.8)}
