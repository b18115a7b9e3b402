"""Scenes render as artists set them up (devkit/material_scenes.py): each feature against an
analytic value or an EEVEE render of the same tiny scene, with the tolerance stated at each
assertion. EEVEE renders at 16 TAA samples; Penumbra at the sample count named per test.

Measured mean |difference| in linear RGB against EEVEE (64x64, 16 samples, Blender 5.2) is
listed in the README's material sheet; the bounds here sit about 2x above those numbers.
"""

import math

import bpy
import numpy as np
import pytest

from devkit import engines, material_scenes, scenes
from devkit.render import render

SIZE = 48


def _penumbra(scene, samples=8):
    engines.configure(scene, "PENUMBRA")
    scene.penumbra.render_samples = samples
    return render(scene)["Combined"]


def _eevee(scene):
    engines.configure(scene, "EEVEE")
    return render(scene)["Combined"]


def _builder(name, size=SIZE):
    return material_scenes.BUILDERS[name](size, size)


def _image_node(scene):
    """The first Image Texture node of the scene's meshes' materials."""
    return next(
        n
        for ob in scene.objects
        if ob.type == "MESH"
        for slot in ob.material_slots
        for n in slot.material.node_tree.nodes
        if n.bl_idname == "ShaderNodeTexImage"
    )


def _against_eevee(name, samples=8, size=SIZE):
    """(Penumbra, EEVEE) renders of builder ``name``."""
    ours = _penumbra(_builder(name, size), samples)
    ref = _eevee(_builder(name, size))
    return ours, ref


def _cell_centres(size, cells):
    """Pixel indices (row, col) of each cell centre of a frame-filling ``cells`` x ``cells``
    grid; cell (i, j): i along +x (columns), j along +y (rows, row 0 at the bottom)."""
    step = size / cells
    return {(i, j): (int((j + 0.5) * step), int((i + 0.5) * step)) for i in range(cells) for j in range(cells)}


# --- textures, colour attributes, node inputs ----------------------------------------------


def test_image_texture_on_base_color_matches_the_analytic_checker(penumbra):
    """Each checker cell's centre is its sRGB colour decoded to linear, lit by a sun of 3 W/m²
    from straight above plus the world's 0.05: albedo * (3 / pi + 0.05), within 0.5 % and the
    GPU's sRGB decode (``srgb_decode_tolerance``: half a code step)."""
    scene = _builder("texture_base_color")
    cells = scene["checker_cells"]
    colours = np.array(scene["checker_srgb"]).reshape(2, 3)
    image = _penumbra(scene, samples=1)
    for (i, j), (row, col) in _cell_centres(SIZE, cells).items():
        shade = 3.0 / math.pi + 0.05
        colour = colours[(i + j) % 2]
        expected = material_scenes.srgb_decoded(colour) * shade
        tolerance = material_scenes.srgb_decode_tolerance(colour) * shade + 0.005 * expected
        assert np.all(np.abs(image[row, col, :3] - expected) <= tolerance), (i, j, image[row, col, :3], expected)


def test_closest_interpolation_and_clip_extension(penumbra):
    """Mapping scales UV by 2 about the centre: the image covers the middle half of the plane,
    one image pixel per cell, drawn with hard edges (Closest); outside it the image is
    transparent black (Clip), so the surface there is black."""
    scene = _builder("texture_closest_clip", 64)
    colours = np.array(scene["checker_srgb"]).reshape(2, 3)
    image = _penumbra(scene, samples=1)
    # Inner region: pixels 16..47 hold 4x4 cells of 8 pixels; every pixel of a cell is exact.
    for i in range(4):
        for j in range(4):
            block = image[16 + 8 * j : 24 + 8 * j, 16 + 8 * i : 24 + 8 * i, :3]
            shade = 3.0 / math.pi + 0.05
            colour = colours[(i + j) % 2]
            expected = material_scenes.srgb_decoded(colour) * shade
            tolerance = material_scenes.srgb_decode_tolerance(colour) * shade + 0.005 * expected
            assert np.all(np.abs(block - expected) <= tolerance), (i, j, block[0, 0], expected)
    border = np.concatenate([image[:16].reshape(-1, 4), image[48:].reshape(-1, 4)])
    assert np.abs(border[:, :3]).max() < 1e-4


def test_color_attribute_matches_eevee(penumbra):
    ours, ref = _against_eevee("color_attribute")
    assert np.abs(ours[..., :3] - ref[..., :3]).mean() < 0.003  # measured 0.0009


def test_emission_shader_is_its_colour_times_strength(penumbra):
    """An Emission shader's surface is exactly colour x strength, with no shading."""
    image = _penumbra(_builder("emission_shader"), samples=1)
    np.testing.assert_allclose(image[SIZE // 2, SIZE // 2, :3], (0.2, 0.6, 1.0), rtol=1e-3)


@pytest.mark.parametrize(
    ("name", "bound"),
    [("emission", 0.02), ("diffuse_bsdf", 0.004), ("rgb_node", 0.015), ("mix_shader", 0.08)],
)
def test_shader_set_ups_match_eevee(penumbra, name, bound):
    """Principled emission adds to the lit surface; a Diffuse BSDF, an RGB node into Base
    Color and a Mix Shader of a Principled and a Glossy BSDF are read (measured 0.009, 0.001,
    0.007, 0.06: the mix of two lobes is drawn as one set of Principled values)."""
    ours, ref = _against_eevee(name)
    assert np.abs(ours[..., :3] - ref[..., :3]).mean() < bound


def test_unsupported_input_falls_back_to_the_viewport_colour_and_says_so(penumbra):
    from penumbra.engine.scene.materials import material_from_blender

    mat, bsdf, _output = material_scenes.node_material("Noisy")
    mat.diffuse_color = (0.1, 0.7, 0.2, 1.0)
    sky = mat.node_tree.nodes.new("ShaderNodeTexSky")
    mat.node_tree.links.new(sky.outputs["Color"], bsdf.inputs["Base Color"])
    read = material_from_blender(mat)
    assert read.base_color[:3] == pytest.approx((0.1, 0.7, 0.2))
    assert len(read.messages) == 1 and "Sky Texture" in read.messages[0] and "Noisy" in read.messages[0]

    toon, _bsdf, _output = material_scenes.node_material("Toon")
    toon.diffuse_color = (0.3, 0.3, 0.9, 1.0)
    material_scenes.replace_shader(toon, "ShaderNodeBsdfToon")
    read = material_from_blender(toon)
    assert read.base_color[:3] == pytest.approx((0.3, 0.3, 0.9))
    assert any("Toon" in m and "viewport display colour" in m for m in read.messages)


def test_material_panel_lists_what_is_drawn_and_what_is_not(penumbra):
    from penumbra.engine.scene.materials import material_from_blender, summary
    from penumbra.ui.panels import PENUMBRA_PT_material

    assert PENUMBRA_PT_material.bl_context == "material" and "PENUMBRA" in PENUMBRA_PT_material.COMPAT_ENGINES
    scene = _builder("alpha_checker_shadow")
    checker = next(ob for ob in scene.objects if ob.name == "Checker")
    mat = checker.material_slots[0].material
    path = mat.node_tree.nodes.new("ShaderNodeLightPath")
    bsdf = next(n for n in mat.node_tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
    mat.node_tree.links.new(path.outputs["Is Camera Ray"], bsdf.inputs["Roughness"])
    lines = summary(material_from_blender(mat))
    assert ("TEXTURE", "Textures: base color, alpha") in lines
    assert ("IMAGE_ALPHA", "Alpha: dithered (hashed over samples)") in lines
    assert [text for icon, text in lines if icon == "ERROR"] == ["Roughness from a 'Light Path' node"]


def test_render_reports_each_unsupported_case_once(penumbra, capfd):
    """Hair is drawn (tests/blender/test_hair.py); what it does not draw is named once a render,
    whatever the number of samples and strands."""
    scene = _builder("hair")
    scene.render.hair_subdiv = 2
    _penumbra(scene, samples=2)
    out = capfd.readouterr().out
    assert "not drawn (hair is not supported)" not in out
    lines = [line for line in out.splitlines() if "Additional Subdivision is not drawn" in line]
    assert len(lines) == 1, out


# --- normal maps, metals, world, light colour ---------------------------------------------


def test_tangent_space_normal_map_tilts_the_normal(penumbra):
    """A constant normal map tilted 30° towards +V under a sun from (0, 1, 1)/sqrt(2): the
    surface sees the sun at 15° instead of 45°: 0.8 * (3 / pi * cos 15° + 0.05), within 1 %."""
    scene = _builder("normal_map")
    image = _penumbra(scene, samples=1)
    expected = 0.8 * (3.0 / math.pi * math.cos(math.radians(15.0)) + 0.05)
    np.testing.assert_allclose(image[8:-8, 8:-8, :3].mean(), expected, rtol=0.01)


def test_normal_map_on_an_ngon_uses_derivative_tangents(penumbra):
    """N-gons have no MikkTSpace tangents: the frame comes from UV derivatives, with the same
    result on a flat surface (and a message)."""
    scene = _builder("normal_map")
    plane = next(ob for ob in scene.objects if ob.type == "MESH")
    # The same plane as one hexagon (two extra vertices on the edges y = -1 and y = 1).
    verts = [(-1, -1, 0), (0, -1, 0), (1, -1, 0), (1, 1, 0), (0, 1, 0), (-1, 1, 0)]
    mesh = bpy.data.meshes.new("Hexagon")
    mesh.from_pydata(verts, [], [tuple(range(6))])
    uv = mesh.uv_layers.new(name="UVMap")
    uv.data.foreach_set("uv", [c for v in verts for c in ((v[0] + 1) / 2, (v[1] + 1) / 2)])
    mesh.materials.append(plane.data.materials[0])
    plane.data = mesh
    assert len(mesh.polygons) == 1 and len(mesh.polygons[0].vertices) == 6
    image = _penumbra(scene, samples=1)
    expected = 0.8 * (3.0 / math.pi * math.cos(math.radians(15.0)) + 0.05)
    np.testing.assert_allclose(image[8:-8, 8:-8, :3].mean(), expected, rtol=0.01)


def test_metal_grid_is_close_to_eevee(penumbra):
    """Roughness x metallic grid of spheres: each sphere's mean colour within 0.13 of EEVEE's,
    and metal at roughness 0.1 reflects the world (not black: the old Blinn gave 0.001)."""
    size = 128
    ours, ref = _against_eevee("metal_grid", size=size)
    assert np.abs(ours[..., :3] - ref[..., :3]).mean() < 0.035  # measured 0.020 (EEVEE-Cycles 0.019)
    step = size // 4
    for r in range(4):
        for c in range(4):
            rows = slice(size - (r + 1) * step + step // 4, size - r * step - step // 4)
            cols = slice(c * step + step // 4, (c + 1) * step - step // 4)
            a, b = ours[rows, cols, :3].mean(axis=(0, 1)), ref[rows, cols, :3].mean(axis=(0, 1))
            # Measured up to 0.17 at these 8 samples (Cycles-EEVEE 0.05): the sphere of metallic
            # 0.67 and roughness 0.1 (row 1, column 0) is brighter than EEVEE's, by 0.15 once
            # converged (64 samples; its highlight of the 0.526 deg sun, sampled at 8 points,
            # moves the 8-sample mean by a few hundredths either way).
            assert np.abs(a - b).max() < 0.2, (r, c, a, b)
    metal = ours[step // 4 : step - step // 4, step // 4 : step - step // 4, :3].mean()  # bottom left
    assert metal > 0.3


def test_environment_texture_world_lights_and_shows_like_eevee(penumbra):
    ours, ref = _against_eevee("world_hdri")
    assert np.abs(ours[..., :3] - ref[..., :3]).mean() < 0.015  # measured 0.003 (5.2), 0.010 (4.5)
    # The background is the image itself: sky above the horizon, ground below.
    np.testing.assert_allclose(ours[-2, 2, :3], (0.6, 1.0, 2.0), rtol=0.02)
    np.testing.assert_allclose(ours[1, 2, :3], (0.4, 0.3, 0.2), rtol=0.02)


def test_light_temperature_colours_the_light(penumbra):
    ours, ref = _against_eevee("light_temperature", samples=1)
    assert np.abs(ours[..., :3] - ref[..., :3]).mean() < 0.003  # measured 0.0008
    r, g, b = ours[SIZE // 2, SIZE // 2, :3]
    assert r > 2.0 * b  # 2000 K is red-orange, not white


# --- alpha ---------------------------------------------------------------------------------


def _alpha_region(image, scene):
    """Pixels well inside the alpha plane (side ``alpha_plane_size`` of a 3-unit view)."""
    half = scene["alpha_plane_size"] / 3.0 / 2.0
    lo, hi = int((0.5 - half * 0.8) * SIZE), int((0.5 + half * 0.8) * SIZE)
    return image[lo:hi, lo:hi, :3]


@pytest.fixture(scope="module")
def alpha_reference():
    """Cycles' render of the alpha plane (transparent shadows: the ground below gets 75 % of
    the sun through it), the region's mean colour."""
    scene = _builder("alpha_blend")
    engines.configure(scene, "CYCLES", samples=64, transparent_max_bounces=8)
    return _alpha_region(render(scene)["Combined"], scene).mean(axis=(0, 1))


@pytest.mark.parametrize("name", ["alpha_quarter", "alpha_blend"])
def test_alpha_covers_a_quarter_and_its_shadow_lets_three_quarters_through(penumbra, name, alpha_reference):
    """Alpha 0.25 over a blue ground, dithered (hashed over 16 stratified samples) or blended:
    0.25 * plane + 0.75 * ground, the ground lit through the plane's shadow by 75 % of the sun
    (alpha shadows are stochastic and converge like the surface). The mean within 0.015 of
    Cycles with transparent shadows; what varies per pixel is the stochastic shadow's noise at
    16 samples (standard deviation < 0.06)."""
    scene = _builder(name)
    ours = _alpha_region(_penumbra(scene, samples=16), scene)
    np.testing.assert_allclose(ours.mean(axis=(0, 1)), alpha_reference, atol=0.015)
    assert ours.std(axis=(0, 1)).max() < 0.06, ours.std(axis=(0, 1))


def test_a_blended_surface_renders_beside_the_passes(penumbra):
    """A blended surface in a final render with Depth and Shadow passes: its variant writes
    the colour target alone (it failed to compile asking for the passes' outputs), Combined
    is the render's without passes, and Depth is the ground's under it (blended surfaces stay
    out of the depth, as in EEVEE): the top view looks down from 10 m."""
    scene = _builder("alpha_blend")
    scene.penumbra.render_samples = 4
    alone = render(scene)["Combined"]
    passes = render(scene, passes=("Combined", "Depth", "Shadow"))
    np.testing.assert_allclose(passes["Combined"], alone, atol=1e-5)
    np.testing.assert_allclose(_alpha_region(passes["Depth"], scene)[..., 0], 10.0, atol=1e-3)


@pytest.mark.parametrize("transparent", [True, False])
def test_alpha_textured_plane_casts_the_analytic_checker_shadow(penumbra, transparent):
    """The ground seen from between it and the checker plane: shadowed exactly under opaque
    cells. Pixels more than one pixel from a cell edge must agree with the analytic pattern.
    With the material's Transparent Shadows off (EEVEE's switch), the whole plane casts, as
    an opaque one."""
    size = 64
    scene = _builder("alpha_checker_shadow", size)
    scene.objects["Checker"].material_slots[0].material.use_transparent_shadow = transparent
    image = _penumbra(scene, samples=1)[..., :3].mean(axis=-1)
    view, cells, side = scene["view_size"], scene["checker_cells"], scene["checker_size"]
    centres = ((np.arange(size) + 0.5) / size - 0.5) * view
    gx, gy = np.meshgrid(centres, centres)  # row 0 at the bottom: y grows with the row
    inside = (np.abs(gx) < side / 2) & (np.abs(gy) < side / 2)
    i = np.floor((gx + side / 2) / (side / cells)).astype(int)
    j = np.floor((gy + side / 2) / (side / cells)).astype(int)
    shadowed = inside & ((i + j) % 2 == scene["checker_opaque_parity"]) if transparent else inside
    cell = side / cells
    pixel = view / size
    fx, fy = np.mod(gx + side / 2, cell), np.mod(gy + side / 2, cell)
    near_edge = (np.minimum(fx, cell - fx) < 1.5 * pixel) | (np.minimum(fy, cell - fy) < 1.5 * pixel)
    near_edge &= transparent  # opaque: only the plane's own border is an edge
    near_edge |= np.abs(np.abs(gx) - side / 2) < 1.5 * pixel
    near_edge |= np.abs(np.abs(gy) - side / 2) < 1.5 * pixel
    lit_level = image[~shadowed & ~near_edge].mean()
    dark = image < 0.5 * lit_level
    assert shadowed.sum() > 200 and (~shadowed & ~near_edge).sum() > 200
    assert np.array_equal(dark[~near_edge], shadowed[~near_edge])


# --- visibility ----------------------------------------------------------------------------


def test_object_visibility_matches_eevee(penumbra):
    """Camera-invisible (only its shadow shows), shadow-invisible (no shadow), holdout (alpha
    0 where it covers) and an emitter with Show Emitter off (only its instances) against
    EEVEE, RGB and alpha."""
    size = 64
    ours = _penumbra(material_scenes.visibility(size, size))
    ref = _eevee(material_scenes.visibility(size, size))
    assert np.abs(ours[..., :3] - ref[..., :3]).mean() < 0.02  # measured 0.010
    assert np.mean(np.abs(ours[..., 3] - ref[..., 3]) > 0.5) < 0.01
    assert (ours[..., 3] < 0.01).sum() > 30  # the holdout's hole is there


def test_holdouts_from_the_view_layer_and_the_holdout_shader(penumbra):
    """Outliner > Holdout on a collection masks its objects in that view layer, an instance
    of a collection takes its instancer's, and a material whose surface is a Holdout shader
    is one: each gives the same image (RGB and alpha) as the object's own Holdout switch."""
    size = 48

    def held_out(how):
        scene = material_scenes.visibility(size, size)
        sphere = scene.objects["Holdout"]
        if how == "object":
            return _penumbra(scene, samples=1)
        sphere.is_holdout = False
        if how == "shader":
            mat = bpy.data.materials.new("Hole")
            mat.use_nodes = True
            nodes = mat.node_tree.nodes
            hole = nodes.new("ShaderNodeHoldout")
            output = next(n for n in nodes if n.bl_idname == "ShaderNodeOutputMaterial")
            mat.node_tree.links.new(hole.outputs[0], output.inputs["Surface"])
            sphere.material_slots[0].material = mat
            return _penumbra(scene, samples=1)
        layers = scene.view_layers[0].layer_collection
        masked = bpy.data.collections.new("Masked")
        scene.collection.children.link(masked)
        if how == "collection":
            scene.collection.objects.unlink(sphere)
            masked.objects.link(sphere)
        else:  # the sphere drawn only through an instance of its (excluded) collection
            source = bpy.data.collections.new("Source")
            scene.collection.children.link(source)
            scene.collection.objects.unlink(sphere)
            source.objects.link(sphere)
            layers.children["Source"].exclude = True
            empty = bpy.data.objects.new("SphereInstance", None)
            empty.instance_type, empty.instance_collection = "COLLECTION", source
            masked.objects.link(empty)
        layers.children["Masked"].holdout = True
        return _penumbra(scene, samples=1)

    own = held_out("object")
    assert (own[..., 3] < 0.01).sum() > 30  # the hole is there
    for how in ("collection", "instance", "shader"):
        np.testing.assert_allclose(held_out(how), own, atol=1e-5, err_msg=how)


# --- model only what a scene requires -----------------------------------------------------


def test_textured_variants_exist_only_for_textured_materials(penumbra):
    from penumbra.engine.frame.programs import lit_program
    from penumbra.engine.scene.materials import material_from_blender

    scene = _builder("texture_base_color")
    plane = next(ob for ob in scene.objects if ob.type == "MESH")
    textured = material_from_blender(plane.material_slots[0].material)
    plain = material_from_blender(bpy.data.materials.new("Plain"))
    assert textured.features == {"TEX_BASE_COLOR"} and plain.features == frozenset()
    assert lit_program(plain.features).samplers == lit_program().samplers  # no texture sampler
    assert [s[1] for s in lit_program(textured.features).samplers][-1] == "tex_base_color"
    assert [v[1] for v in lit_program(textured.features).vertex_in] == ["pos", "nor", "uv"]


def test_images_upload_once_and_reupload_after_an_update(penumbra, gpu_call):
    """Two frames of a textured scene upload its one image once and read its material once;
    after a depsgraph update of the image (Blender's own, through SceneCache.apply_updates),
    the next frame uploads it again."""
    scene = _builder("texture_base_color")
    image = bpy.data.images[0]

    def job(engine, depsgraph):
        from penumbra.engine.scene.extract import camera_from_scene

        camera = camera_from_scene(depsgraph, scene, SIZE, SIZE)
        for _ in range(2):
            engine.render_frame(depsgraph, camera, SIZE, SIZE)
        counts = [engine.renderer.textures.uploads, engine.cache.materials_read]
        engine.cache.images_changed.add(image.name_full)  # what apply_updates records (below)
        engine.render_frame(depsgraph, camera, SIZE, SIZE)
        return counts + [engine.renderer.textures.uploads]

    assert gpu_call(job) == [1, 1, 2]

    from penumbra.engine.scene.extract import SceneCache

    cache = SceneCache()
    cache.snapshot(bpy.context.evaluated_depsgraph_get())
    cache.images_changed.clear()

    def handler(_scene, depsgraph):
        cache.apply_updates(depsgraph)

    bpy.app.handlers.depsgraph_update_post.append(handler)
    try:
        image.pixels[0] = 0.5
        image.update_tag()
        bpy.context.view_layer.update()
    finally:
        bpy.app.handlers.depsgraph_update_post.remove(handler)
    assert cache.images_changed == {image.name_full}


def test_images_drawn_in_part_are_named(penumbra, gpu_call, capfd):
    """An image wider than the GPU's textures is drawn reduced by Blender, and a UDIM image
    draws its first tile: each is named once in the render report, and the reduced image's
    colour is still drawn (a uniform image reads the same at any size)."""
    import gpu

    limit = gpu_call(lambda engine, depsgraph: gpu.capabilities.max_texture_size_get())
    scene = _builder("texture_base_color")
    node = _image_node(scene)
    wide = bpy.data.images.new("Wide", limit + 1, 2, alpha=True)
    wide.generated_color = (0.8, 0.2, 0.1, 1.0)
    node.image = wide
    image = _penumbra(scene, samples=1)
    out = capfd.readouterr().out
    assert f"Penumbra: image 'Wide' ({limit + 1}x2) is larger than this GPU's textures" in out
    centre = image[SIZE // 2, SIZE // 2, :3]
    assert centre[0] > 5 * centre[2]  # its red, not magenta

    tiles = bpy.data.images.new("Tiles", 8, 8, alpha=True, tiled=True)
    tiles.tiles.new(1002)
    node.image = tiles
    _penumbra(scene, samples=1)
    out = capfd.readouterr().out
    assert "Penumbra: image 'Tiles' has UDIM tiles: only tile 1001 is drawn" in out


@pytest.mark.negative_inputs  # a texel of -inf, on purpose
def test_bad_texture_inputs_render_finite_with_messages(penumbra, capfd):
    """A float image with NaN/Inf texels, an image whose file is missing, and a mesh without
    the UV map a texture asks for: the frame is finite, the missing image draws magenta (as in
    Blender), and each case is named."""
    scene = _builder("texture_base_color")
    plane = next(ob for ob in scene.objects if ob.type == "MESH")
    bad = bpy.data.images.new("BadFloat", 4, 4, float_buffer=True)
    px = np.full((4, 4, 4), 0.5, np.float32)
    px[0, 0] = (np.nan, np.inf, -np.inf, 1.0)
    bad.pixels.foreach_set(px.ravel())
    mat = plane.material_slots[0].material
    node = next(n for n in mat.node_tree.nodes if n.bl_idname == "ShaderNodeTexImage")
    node.image = bad
    image = _penumbra(scene, samples=1)
    assert np.isfinite(image).all()

    missing = bpy.data.images.new("Missing", 8, 8)
    missing.source = "FILE"
    missing.filepath = "/nonexistent/texture.png"
    node.image = missing
    plane.data.uv_layers.remove(plane.data.uv_layers[0])
    image = _penumbra(scene, samples=1)
    out = capfd.readouterr()
    assert np.isfinite(image).all()
    centre = image[SIZE // 2, SIZE // 2, :3]
    assert centre[0] > 5 * centre[1] and centre[2] > 5 * centre[1]  # magenta
    assert "Warning: Penumbra: image 'Missing' has no pixels (missing file?): drawn magenta" in out.out
    assert "Penumbra: mesh 'Plane' has no UV map: its textures read UV (0, 0)" in out.out


@pytest.fixture(scope="module")
def eevee_emission(penumbra):
    return render(engines.configure(_builder("emission"), "EEVEE"), passes=("Combined", "Emission"))["Emission"]


@pytest.mark.parametrize("samples", [1, 4])
def test_emission_pass_is_what_surfaces_emit(penumbra, samples, eevee_emission):
    """The Emission pass (View Layer > Passes > Emission) holds each surface's emission
    (colour x strength, 0 elsewhere), averaged over samples like Combined: on the emissive
    sphere it equals EEVEE's, and it is anti-aliased like Combined."""
    scene = engines.configure(_builder("emission"), "PENUMBRA", render_samples=samples)
    ours = render(scene, passes=("Combined", "Emission"))
    emit = ours["Emission"]
    centre = emit[SIZE // 2, SIZE // 2, :3]
    np.testing.assert_allclose(centre, (2.0, 1.0, 0.4), rtol=1e-3)  # (1, 0.5, 0.2) x strength 2
    assert np.abs(emit[:3, :3]).max() == 0.0  # the background emits nothing
    ref = eevee_emission
    inside = np.abs(ref[..., :3] - np.array((2.0, 1.0, 0.4))).max(axis=-1) < 1e-3
    assert inside.sum() > 0.2 * SIZE * SIZE
    np.testing.assert_allclose(emit[inside, :3], ref[inside, :3], rtol=1e-3)
    if samples > 1:  # anti-aliased like Combined: edge pixels are partial
        partial = (emit[..., 0] > 0.05) & (emit[..., 0] < 1.95)
        assert partial.sum() > 10


def test_final_renders_draw_blenders_own_image_texture(penumbra):
    """Final renders (a new engine each) draw an image through Blender's own GPU texture: no
    render reads its pixels into Python or hashes them (tracemalloc sees nothing near the
    image's size allocated, the first render included; the old path read a float32 copy of
    every pixel each render), and pixels edited in memory show in the next render, saved or
    not, as do a changed colour space."""
    import tracemalloc

    scene = _builder("texture_base_color")
    node = _image_node(scene)
    size = 1024
    image = bpy.data.images.new("Large", size, size, alpha=True)
    rng = np.random.default_rng(3)
    pixels = np.repeat(rng.random((size * size, 1), dtype=np.float32), 4, axis=1)
    pixels[:, 3] = 1.0
    image.pixels.foreach_set(pixels.ravel())
    node.image = image
    image_bytes = size * size * 4 * 4
    peaks = []
    renders = []
    for _ in range(2):
        tracemalloc.start()
        renders.append(_penumbra(scene, samples=1))
        peaks.append(tracemalloc.get_traced_memory()[1])
        tracemalloc.stop()
    assert max(peaks) < image_bytes / 8, peaks
    np.testing.assert_array_equal(renders[0], renders[1])

    pixels[:, :3] = 0.0  # edited in memory, not saved: black
    image.pixels.foreach_set(pixels.ravel())
    edited = _penumbra(scene, samples=1)
    assert edited[..., :3].max() < 0.25 * renders[0][..., :3].max()
    pixels[:, :3] = 0.5
    image.pixels.foreach_set(pixels.ravel())
    srgb = _penumbra(scene, samples=1)
    # The same pixels read another way: brighter. (A generated image is made anew when its
    # colour space changes, in every engine: its pixels are set again.)
    image.colorspace_settings.name = "Non-Color"
    image.pixels.foreach_set(pixels.ravel())
    other = _penumbra(scene, samples=1)
    assert other[..., :3].mean() > 1.5 * srgb[..., :3].mean()


def test_the_renderer_takes_the_image_texture_blender_made(penumbra, gpu_call):
    """The texture the lit pass binds is the one ``gpu.texture.from_image`` gives (Blender's,
    with its mipmaps), taken once per image; a depsgraph update of the image takes it again."""
    import gpu

    scene = _builder("texture_base_color")
    image = next(i for i in bpy.data.images if i.users and i.size[0] > 0)

    def job(engine, depsgraph):
        from penumbra.engine.scene.extract import camera_from_scene

        camera = camera_from_scene(depsgraph, scene, SIZE, SIZE)
        engine.render_frame(depsgraph, camera, SIZE, SIZE)
        textures = engine.renderer.textures
        ours = textures.get(image.name_full)
        return ours == gpu.texture.from_image(image), textures.uploads

    same, uploads = gpu_call(job)
    assert same and uploads == 1


@pytest.mark.parametrize("node", ["ShaderNodeMix", "ShaderNodeMixRGB"])
def test_a_texture_multiplied_by_a_colour_is_drawn_tinted(penumbra, node):
    """Image Texture x a constant colour through a Mix (Color) node set to Multiply, factor
    0.75: per channel the image's render times 1 - f + f B, on a surface without specular
    (diffuse light is linear in the albedo), and nothing named as unsupported."""
    from penumbra.engine.scene.materials import material_from_blender

    tint = (0.5, 0.8, 1.0)

    def render_plane(tinted):
        scene = scenes.empty_scene(32, 32)
        image = bpy.data.images.new("Checks", 8, 8)
        cells = np.indices((8, 8)).sum(axis=0) % 2
        pixels = np.ones((8, 8, 4), np.float32)
        pixels[..., :3] = np.where(cells[..., None], 0.9, 0.2)
        image.pixels.foreach_set(pixels.ravel())
        mat = scenes.material("Tex", (0.8, 0.8, 0.8), roughness=1.0, specular=0.0)
        nodes, links = mat.node_tree.nodes, mat.node_tree.links
        bsdf = next(n for n in nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
        tex = nodes.new("ShaderNodeTexImage")
        tex.image, tex.interpolation = image, "Closest"
        if tinted:
            mix = nodes.new(node)
            mix.blend_type = "MULTIPLY"
            if node == "ShaderNodeMix":
                mix.data_type = "RGBA"
                sockets = {s.identifier: s for s in mix.inputs}
                fac, a, b, result = sockets["Factor_Float"], sockets["A_Color"], sockets["B_Color"], mix.outputs[2]
            else:
                fac, a, b, result = mix.inputs[0], mix.inputs["Color1"], mix.inputs["Color2"], mix.outputs[0]
            fac.default_value = 0.75
            b.default_value = (*tint, 1.0)
            links.new(tex.outputs["Color"], a)
            links.new(result, bsdf.inputs["Base Color"])
        else:
            links.new(tex.outputs["Color"], bsdf.inputs["Base Color"])
        material_scenes.uv_plane(scene, size=2.0, mat=mat)
        scenes.light(scene, "Sun", "SUN", 3.0)
        scenes.top_camera(scene, height=5.0, ortho_scale=1.8)
        read = material_from_blender(mat)
        return _penumbra(scene, samples=1), read

    plain, _ = render_plane(False)
    tinted, read = render_plane(True)
    assert "base_color" in read.textures and not read.messages
    expected = plain[..., :3] * (1.0 - 0.75 + 0.75 * np.array(tint))
    assert plain[..., :3].max() > 0.3
    np.testing.assert_allclose(tinted[..., :3], expected, rtol=1e-4, atol=1e-5)


@pytest.mark.parametrize(
    "node, factor",
    [("ShaderNodeSeparateColor", None), ("ShaderNodeSeparateRGB", None), ("ShaderNodeSeparateColor", 0.5)],
)
def test_separate_color_reads_one_component_of_an_image(penumbra, node, factor):
    """A packed (glTF-style) map: an image's G into Roughness and B into Metallic through a
    Separate Color node gives the render of those constants (0.75 and 0.25), not of the
    image's luminance; with a Math Multiply by 0.5 between G and Roughness (the glTF
    importer's roughness factor), that of roughness 0.375."""
    if not hasattr(bpy.types, node):
        pytest.skip(f"{node} does not exist in Blender {bpy.app.version_string}")
    from penumbra.engine.scene.materials import material_from_blender

    def render_plane(packed):
        scene = scenes.empty_scene(32, 32)
        roughness = 0.75 * (factor or 1.0)
        mat = scenes.material("M", (0.8, 0.5, 0.3), roughness=roughness, specular=0.5, metallic=0.25)
        if packed:
            image = bpy.data.images.new("Packed", 4, 4, float_buffer=True)
            image.colorspace_settings.is_data = True
            image.pixels.foreach_set(np.tile([0.5, 0.75, 0.25, 1.0], 16).astype(np.float32))
            nodes, links = mat.node_tree.nodes, mat.node_tree.links
            bsdf = next(n for n in nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
            tex, split = nodes.new("ShaderNodeTexImage"), nodes.new(node)
            tex.image = image
            links.new(tex.outputs["Color"], split.inputs[0])
            if factor is None:
                links.new(split.outputs[1], bsdf.inputs["Roughness"])
            else:
                scale = nodes.new("ShaderNodeMath")
                scale.operation = "MULTIPLY"
                scale.inputs[1].default_value = factor
                links.new(split.outputs[1], scale.inputs[0])
                links.new(scale.outputs[0], bsdf.inputs["Roughness"])
            links.new(split.outputs[2], bsdf.inputs["Metallic"])
        material_scenes.uv_plane(scene, size=2.0, mat=mat)
        scenes.light(scene, "Lamp", "POINT", 30.0, location=(0.4, -0.3, 1.5))
        scenes.camera(scene, (0.0, -2.0, 3.0), (math.radians(34), 0.0, 0.0), ortho_scale=2.0, clip=(0.1, 10.0))
        return _penumbra(scene, samples=1), material_from_blender(mat)

    constant, _ = render_plane(False)
    packed, read = render_plane(True)
    assert {"roughness", "metallic"} <= set(read.textures) and not read.messages
    assert constant[..., :3].max() > 0.1
    np.testing.assert_allclose(packed, constant, rtol=1e-4, atol=1e-5)


# --- IOR, Specular IOR Level, Specular Tint ------------------------------------------------

MIRROR_WORLD = 0.5  # the constant world a mirror-smooth black tile reflects, seen head-on


def _tile_grid(scene, mats, columns):
    """Unit tiles of ``mats`` in a grid of ``columns`` under an orthographic top camera (the
    camera looks at every tile head-on: normal incidence); -> (row, col) pixel of each."""
    size = scene.render.resolution_x
    rows = math.ceil(len(mats) / columns)
    scale = max(columns, rows) + 0.5
    centres = []
    for k, mat in enumerate(mats):
        x, y = k % columns - (columns - 1) / 2, k // columns - (rows - 1) / 2
        corners = [(-0.5, -0.5, 0.0), (0.5, -0.5, 0.0), (0.5, 0.5, 0.0), (-0.5, 0.5, 0.0)]
        ob = scenes.mesh_object(scene, f"Tile{k}", corners, [(0, 1, 2, 3)], location=(x, y, 0.0), mat=mat)
        layer = ob.data.uv_layers.new(name="UVMap")
        layer.data.foreach_set("uv", [0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0, 1.0])
        centres.append((int(size / 2 + y * size / scale), int(size / 2 + x * size / scale)))
    scenes.camera(scene, (0.0, 0.0, 5.0), (0.0, 0.0, 0.0), ortho_scale=scale, clip=(0.1, 10.0))
    return centres


def _mirror(name, ior, level=0.5, tint=None):
    """A black mirror-smooth Principled surface of that IOR, Specular IOR Level and tint."""
    mat = scenes.material(name, (0.0, 0.0, 0.0), roughness=0.0, specular=level)
    bsdf = mat.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["IOR"].default_value = ior
    if tint is not None:
        bsdf.inputs["Specular Tint"].default_value = (*tint, 1.0)
    return mat, bsdf


def _reflected(image, centre):
    r, c = centre
    return image[r - 1 : r + 2, c - 1 : c + 2, :3].mean(axis=(0, 1)) / MIRROR_WORLD


@pytest.mark.parametrize("compiled", [False, True])
def test_ior_and_specular_ior_level_give_blenders_f0(penumbra, compiled):
    """A black mirror tile reflects the constant world head-on by F0 = ((ior - 1) / (ior +
    1))^2 x 2 x Specular IOR Level (clamped to 1), as Cycles' and EEVEE's Principled BSDF: IOR
    1.1, 1.5, 3 and 1000 at levels 0.25, 0.5 and 1, through the reader and (IOR from a Math
    node) through the compiled tree. Within 0.007 + 2 % of F0: Penumbra's split-sum fit adds
    up to 0.006 at low F0 (measured at most 0.0058 on Blender 5.2 and 4.5; EEVEE's render of
    the same tiles is within 0.0006 of the analytic F0)."""
    from penumbra.engine.scene.materials import material_from_blender

    scene = scenes.empty_scene(48, 48)
    scenes.set_world(scene, (MIRROR_WORLD,) * 3)
    cases = [(ior, level) for ior in (1.1, 1.5, 3.0, 1000.0) for level in (0.25, 0.5, 1.0)]
    mats = []
    for k, (ior, level) in enumerate(cases):
        mat, bsdf = _mirror(f"Mirror{k}", ior, level)
        if compiled:
            add = mat.node_tree.nodes.new("ShaderNodeMath")
            add.operation = "ADD"
            add.inputs[0].default_value, add.inputs[1].default_value = ior, 0.0
            mat.node_tree.links.new(add.outputs[0], bsdf.inputs["IOR"])
        read = material_from_blender(mat)
        assert (read.tree is not None) == compiled and not read.messages, read.messages
        mats.append(mat)
    centres = _tile_grid(scene, mats, 3)
    image = _penumbra(scene, samples=1)
    f0 = np.array([min(((n - 1) / (n + 1)) ** 2 * 2 * level, 1.0) for n, level in cases])
    got = np.array([_reflected(image, c) for c in centres])
    assert np.allclose(got, got[:, :1], atol=1e-4)  # grey: no tint
    np.testing.assert_allclose(got[:, 0], f0, atol=0.007, rtol=0.02)
    at_half = got[1::3, 0]  # level 0.5: IOR 1.1, 1.5, 3, 1000
    assert np.all(np.diff(at_half) > 0.02), at_half  # the IOR is drawn, not a fixed 0.04


def test_specular_tint_colours_the_reflection_constant_and_from_an_image(penumbra):
    """Specular Tint multiplies F0 (white F90): at IOR 1000 (the glTF specular-glossiness
    import) a black mirror reflects the world by 0.996 x tint, per channel; a constant tint is
    read by the reader, an image into Specular Tint is drawn by the compiled tree; at IOR 1.5 a
    tint of (1, 0.5, 0) gives F0 (0.04, 0.02, 0). Neither says "not drawn". Within 0.007 + 2 %
    (measured at most 0.006 on Blender 5.2 and 4.5)."""
    from penumbra.engine.scene.materials import material_from_blender

    scene = scenes.empty_scene(48, 48)
    scenes.set_world(scene, (MIRROR_WORLD,) * 3)
    constant, _ = _mirror("Constant", 1000.0, tint=(1.0, 0.3, 0.1))
    textured, bsdf = _mirror("Textured", 1000.0)
    colour = (0.2, 0.9, 0.4)
    img = material_scenes.image("Tint", np.tile(np.float32([*colour, 1.0]), (4, 4, 1)), float_buffer=True)
    tex = material_scenes.image_node(textured, img)
    textured.node_tree.links.new(tex.outputs["Color"], bsdf.inputs["Specular Tint"])
    low, _ = _mirror("Low", 1.5, tint=(1.0, 0.5, 0.0))
    plain = _mirror("Plain", 1000.0)[0]
    reads = [material_from_blender(m) for m in (constant, textured, low, plain)]
    assert [r.tree is not None for r in reads] == [False, True, False, False]
    assert not any(r.messages for r in reads), [r.messages for r in reads]
    centres = _tile_grid(scene, [constant, textured, low, plain], 2)
    image = _penumbra(scene, samples=1)
    got = [_reflected(image, c) for c in centres]
    f0 = (999.0 / 1001.0) ** 2
    expected = [f0 * np.array((1.0, 0.3, 0.1)), f0 * np.array(colour), np.array((0.04, 0.02, 0.0)), np.full(3, f0)]
    for g, e in zip(got, expected, strict=True):
        np.testing.assert_allclose(g, e, atol=0.007, rtol=0.02)
