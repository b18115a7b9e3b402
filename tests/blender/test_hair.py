"""Hair: Curves objects and particle hair drawn as strips facing the camera, shaded by their
material, casting shadows from strips facing the light (engine/scene/hair.py). The scene is
``devkit.material_scenes.hair_patch``: 2500 curve strands over a white ground beside a sphere
with particle hair and interpolated children, under a sun from +x.

Measured on llvmpipe (Blender 5.2, 240x135, Penumbra 8 samples, EEVEE 16): mean |display
difference| against EEVEE 0.026 seen from the front, 0.018 from the top."""

import bpy
import numpy as np
import pytest

from devkit import engines, material_scenes
from devkit.render import render

WIDTH, HEIGHT = 240, 135
SCALE = 3.2  # the top camera's orthographic scale: metres across the frame


def _display(image):
    c = np.clip(image[..., :3], 0.0, 1.0)
    return np.where(c <= 0.0031308, 12.92 * c, 1.055 * c ** (1.0 / 2.4) - 0.055)


def _render(engine, samples=8, edit=None, **kw):
    scene = material_scenes.hair_patch(WIDTH, HEIGHT, **kw)
    if edit is not None:
        edit(scene)
    engines.configure(scene, engine)
    if engine == "PENUMBRA":
        scene.penumbra.render_samples = samples
        # Against EEVEE, which does not occlude the world's light by the strands (with
        # Penumbra's world shadows the dense patch is 0.07 in display against EEVEE's 0.16).
        scene.penumbra.world_shadows = False
        scene.penumbra.world_ao = False
    return render(scene)["Combined"]


def _region(x0, x1, y0, y1):
    """Pixel slices (rows, columns) of the ground rectangle [x0, x1] x [y0, y1] in the top view."""
    span_y = SCALE * HEIGHT / WIDTH

    def px(v, lo, span, n):
        return int(round((v - lo) / span * n))

    rows = slice(px(y0, -span_y / 2, span_y, HEIGHT), px(y1, -span_y / 2, span_y, HEIGHT))
    cols = slice(px(x0, -SCALE / 2, SCALE, WIDTH), px(x1, -SCALE / 2, SCALE, WIDTH))
    return rows, cols


# Where the strands stand, where their shadow falls (the sun is at +x: the shadow lies toward
# -x, up to 0.5 m beyond the patch), and open ground.
PATCH = _region(-0.35, 0.35, -0.35, 0.35)
SHADOW = _region(-0.95, -0.6, -0.3, 0.3)
GROUND = _region(0.95, 1.4, -0.3, 0.3)


def test_hair_matches_eevee(penumbra):
    """Curves and particle hair (children included) against EEVEE: mean |display difference|
    at most 0.05 (measured 0.026)."""
    ours = _render("PENUMBRA")
    ref = _render("EEVEE")
    assert np.abs(_display(ours) - _display(ref)).mean() <= 0.05


def test_hair_is_drawn_and_shadows_the_ground(penumbra):
    """Seen from the top: the patch is covered by dark strands as in EEVEE (within 0.06 of its
    mean display value); their shadow darkens the ground beside them, as in EEVEE (measured on
    5.2: by 15 %, EEVEE 6 %), by at least 10 %; with the strands' Ray Visibility > Shadow off
    the ground there is unshadowed."""
    ours = _display(_render("PENUMBRA", particles=False, top=True))
    ref = _display(_render("EEVEE", particles=False, top=True))
    ground = ours[GROUND].mean()
    assert ours[PATCH].mean() < 0.5 * ground  # drawn: brown strands over white ground
    assert abs(ours[PATCH].mean() - ref[PATCH].mean()) <= 0.06
    shadow, ref_shadow = ours[SHADOW].mean() / ground, ref[SHADOW].mean() / ref[GROUND].mean()
    assert shadow < 0.9 and ref_shadow < 0.97
    assert abs(shadow - ref_shadow) <= 0.15

    def no_shadow(scene):
        scene.objects["Strands"].visible_shadow = False

    unshadowed = _display(_render("PENUMBRA", particles=False, top=True, edit=no_shadow))
    assert unshadowed[SHADOW].mean() == pytest.approx(unshadowed[GROUND].mean(), rel=0.02)


def test_hair_hidden_from_the_camera_still_shadows(penumbra):
    """Ray Visibility > Camera off: the strands are not drawn, their shadow stays."""

    def hidden(scene):
        scene.objects["Strands"].visible_camera = False

    image = _display(_render("PENUMBRA", samples=2, particles=False, top=True, edit=hidden))
    red, blue = image[PATCH][..., 0].mean(), image[PATCH][..., 2].mean()
    assert abs(red - blue) < 0.01  # grey ground (in the strands' shadow), no brown strand
    assert image[SHADOW].mean() < 0.9 * image[GROUND].mean()


def test_strip_shape_draws_the_radius(penumbra):
    """Render > Curves > Shape Strip: strands as wide as their radius says. Wider strands cover
    more of the patch; the Strand shape is a pixel wide whatever the radius."""

    def shape(kind, radius):
        def edit(scene):
            scene.render.hair_type = kind
            values = np.full(len(scene.objects["Strands"].data.points), radius, np.float32)
            scene.objects["Strands"].data.attributes["radius"].data.foreach_set("value", values)

        return _display(_render("PENUMBRA", samples=2, particles=False, top=True, edit=edit))[PATCH].mean()

    thin, thick = shape("STRIP", 0.001), shape("STRIP", 0.004)
    assert thick < thin - 0.05
    assert shape("STRAND", 0.001) == pytest.approx(shape("STRAND", 0.004), abs=0.01)


def test_particle_hair_follows_render_steps_and_children(penumbra):
    """Particle hair is read from the evaluated path cache: 2^steps + 1 points per strand, and
    only the children when children are on (``hair.geometry_from_particles``)."""
    from penumbra.engine.scene import hair

    scene = material_scenes.hair_patch(WIDTH, HEIGHT)
    body = scene.objects["HairBall"]
    depsgraph = bpy.context.evaluated_depsgraph_get()
    ev = body.evaluated_get(depsgraph)
    psys = hair.particle_hair(ev, render=False)[0]
    geo = hair.geometry_from_particles(ev, psys, render=False)
    steps = 1 << psys.settings.display_step
    strands = len(psys.child_particles)
    assert strands == psys.settings.count * psys.settings.child_percent
    assert len(geo.positions) == 2 * strands * (steps + 1)
    assert geo.triangle_count == 2 * strands * steps
    # Object space: the strands start on the sphere (radius 0.35 about the object's origin).
    roots = geo.positions[0 :: 2 * (steps + 1)]
    np.testing.assert_allclose(np.linalg.norm(roots, axis=1), 0.35, atol=0.02)


def test_hair_bsdf_is_drawn_as_a_diffuse_of_its_colour(penumbra):
    """A Hair BSDF (or a Principled Hair BSDF by colour) is a diffuse surface of its colour,
    named; by melanin, the viewport display colour, named."""
    from penumbra.engine.scene.materials import material_from_blender

    for kind in ("ShaderNodeBsdfHair", "ShaderNodeBsdfHairPrincipled"):
        mat = bpy.data.materials.new(kind)
        mat.use_nodes = True
        tree = mat.node_tree
        output = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputMaterial")
        node = tree.nodes.new(kind)
        node.inputs["Color"].default_value = (0.3, 0.2, 0.1, 1.0)
        tree.links.new(node.outputs[0], output.inputs["Surface"])
        read = material_from_blender(mat)
        assert read.base_color[:3] == pytest.approx((0.3, 0.2, 0.1))
        assert read.specular == 0.0 and any("diffuse surface of its colour" in m for m in read.messages)
    node.parametrization = "MELANIN"
    read = material_from_blender(mat)
    assert read.base_color[:3] == pytest.approx(tuple(mat.diffuse_color)[:3])
    assert any("melanin" in m for m in read.messages)


def test_strips_and_catmull_rom(penumbra):
    """Catmull-Rom evaluation passes through its control points (Blender's uniform basis, end
    points repeated); strips have two vertices a point, two triangles a segment, bounds
    padded by the radius, and material ranges by curve."""
    from penumbra.engine.scene import hair

    points = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 1], [5, 5, 5], [6, 5, 5]], np.float64)
    offsets = np.array([0, 4, 6])
    out, out_offsets, values = hair.catmull_rom(points, offsets, np.arange(6.0)[:, None], [4, 4])
    assert list(out_offsets) == [0, 13, 18]
    np.testing.assert_allclose(out[[0, 4, 8, 12, 13, 17]], points, atol=1e-12)
    np.testing.assert_allclose(values[[0, 4, 8, 12]].ravel(), [0, 1, 2, 3], atol=1e-12)
    np.testing.assert_allclose(out[13:18, 1:], 5.0, atol=1e-12)  # two points: on their line
    assert np.all(np.diff(out[13:18, 0]) > 0.0)
    geo = hair.strips(points, offsets, np.full(6, 0.1), curve_materials=[1, 0])
    assert len(geo.positions) == 12 and geo.triangle_count == 2 * (3 + 1)
    assert geo.ranges == [(0, 0, 2), (1, 2, 6)]
    np.testing.assert_allclose(geo.bounds, [[-0.1, -0.1, -0.1], [6.1, 5.1, 5.1]], atol=1e-6)
    assert set(geo.strands[:, 0]) == {-1.0, 1.0}


def test_hair_with_alpha_names_its_solid_shadow(penumbra, capfd):
    """Strands whose material has alpha cast solid shadows (the strips' shadow program has no
    alpha): the render report says so, once; opaque strands say nothing of it."""

    def translucent(scene):
        mat = scene.objects["Strands"].data.materials[0]
        bsdf = next(n for n in mat.node_tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
        bsdf.inputs["Alpha"].default_value = 0.5

    capfd.readouterr()
    _render("PENUMBRA", samples=1, particles=False, top=True)
    assert "alpha is not drawn in shadows" not in capfd.readouterr().out
    _render("PENUMBRA", samples=1, particles=False, top=True, edit=translucent)
    out = capfd.readouterr().out
    assert out.count("hair of 'Strands': its material's alpha is not drawn in shadows") == 1, out[-2000:]
