"""The Principled BSDF's sheen (shaders/lib/sheen.glsl) against the same lobe in numpy
(devkit.analytic.sheen_reflectance: Zeltner, Burley and Chiang's linearly transformed cosine
with the table tools/make_sheen_table.py measured from Cycles) and against Cycles itself. A
plane fills an orthographic view, so every pixel sees the same angles and the image mean is one
evaluation of the BSDF."""

import math

import numpy as np
import pytest

from devkit import analytic, scenes
from devkit.plane_scenes import SUN, WORLD, plane_mean, plane_scene
from devkit.plane_scenes import directions as _directions
from devkit.render import debug_view_mean, group_off_and_on


def _material(base, sheen_rough, weight=1.0, tint=(1.0, 1.0, 1.0), specular=0.0):
    mat = scenes.material("Sheen", (base, base, base), roughness=0.5, specular=specular)
    bsdf = mat.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Sheen Weight"].default_value = weight
    bsdf.inputs["Sheen Roughness"].default_value = sheen_rough
    bsdf.inputs["Sheen Tint"].default_value = (*tint, 1.0)
    return mat


def _plane_scene(make, view_deg, sun_elevation=None, sun_azimuth=0.0):
    return plane_scene(make, view_deg, sun_elevation, sun_azimuth)


def _plane(make, view_deg, sun_elevation=None, samples=4, sun_azimuth=0.0):
    return plane_mean(make, view_deg, sun_elevation, samples, sun_azimuth)


@pytest.mark.parametrize(
    ("sheen_rough", "view", "elevation", "azimuth"),
    [(0.3, 70, 30, 0.0), (0.6, 45, 50, 2.0), (1.0, 60, 20, 3.0), (0.5, 80, 60, 1.0)],
)
def test_the_sheen_under_a_sun_is_the_lobe(penumbra, sheen_rough, view, elevation, azimuth):
    """A black base without specular under a sheen of weight 1: what a sun lights is R D of
    the lobe in numpy, within 2 % (one sample: the lobe is exact, not estimated)."""
    v, to_light = _directions(view, elevation, azimuth)
    ref = SUN * analytic.sheen_reflectance(sheen_rough, v, to_light)
    assert ref > 1e-3
    ours = _plane(lambda: _material(0.0, sheen_rough), view, elevation, samples=1, sun_azimuth=azimuth)
    assert np.allclose(ours, ref, rtol=0.02), (ours, ref)


def test_the_sheen_matches_cycles_between_the_tables_nodes(penumbra):
    """The table is measured from Cycles at its nodes; between them (roughness 0.45, a view at
    55 degrees, a sun off the view's plane) the sheen alone under a sun is Cycles' own within
    3 % (Cycles at one sample: a sun at angle 0 is sampled exactly)."""
    view, elevation, azimuth = 55, 35, 2.4
    ours = _plane(lambda: _material(0.0, 0.45), view, elevation, samples=1, sun_azimuth=azimuth)
    cycles = plane_mean(lambda: _material(0.0, 0.45), view, elevation, 1, azimuth, engine="CYCLES")
    assert cycles.mean() > 1e-3
    assert np.allclose(ours, cycles, rtol=0.03), (ours, cycles)


@pytest.mark.parametrize("tint", [(1.0, 1.0, 1.0), (0.2, 0.6, 1.0)])
def test_the_sheen_over_a_base_keeps_what_it_does_not_reflect(penumbra, tint):
    """A red diffuse (no specular) under a tinted sheen, under a sun: the base keeps
    1 - max(tint R) of its light (Cycles' layering), the sheen adds tint R D, within 2 %."""
    view, elevation = 65, 40
    v, to_light = _directions(view, elevation)
    mat_color = np.array([0.6, 0.1, 0.05])
    a, b, r = analytic.sheen_ltc(0.5, v[2])
    below = 1.0 - max(np.array(tint) * r)
    base = mat_color * to_light[2] / math.pi
    ref = SUN * (below * base + np.array(tint) * analytic.sheen_reflectance(0.5, v, to_light))

    def make():
        mat = _material(0.0, 0.5, tint=tint)
        mat.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (*mat_color, 1.0)
        return mat

    ours = _plane(make, view, elevation, samples=1)
    assert np.allclose(ours, ref, rtol=0.02), (ours, ref)


@pytest.mark.parametrize(("sheen_rough", "view"), [(0.3, 75), (1.0, 40), (0.7, 85)])
def test_the_sheen_in_a_uniform_world_reflects_its_albedo(penumbra, sheen_rough, view):
    """Under a uniform world the sheen alone sends back R (its lobe integrates to 1) of it,
    within 1 %; over a white diffuse it sends back the world exactly (1 - R below, R above),
    within 0.5 %."""
    mu = math.cos(math.radians(view))
    r = analytic.sheen_ltc(sheen_rough, mu)[2]
    assert r > 0.05
    alone = _plane(lambda: _material(0.0, sheen_rough), view, samples=8)
    assert np.allclose(alone, WORLD * r, rtol=0.01), (alone, WORLD * r)
    white = _plane(lambda: _material(1.0, sheen_rough), view, samples=8)
    assert np.allclose(white, WORLD, rtol=0.005), white


def test_the_sheens_table_is_a_normalised_lobe():
    """Every cell's transformed cosine integrates to 1 over the hemisphere (within the
    quadrature's 0.5 %), its albedo R lies in [0, 1] and grows towards grazing views and with
    roughness at normal incidence (Zeltner et al.'s figure 5)."""
    table = analytic.sheen_table()
    n = 300
    th = (np.arange(n) + 0.5) / n * np.pi / 2
    ph = (np.arange(2 * n) + 0.5) / (2 * n) * 2 * np.pi
    t, p = np.meshgrid(th, ph, indexing="ij")
    d = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], -1)
    dw = np.sin(t) * (np.pi / 2 / n) * (np.pi / n)
    for k in range(0, table.shape[0], 3):
        for j in range(0, table.shape[1], 3):
            a, b, r = table[k, j]
            if r > 0.0:
                assert (analytic.sheen_lobe(a, b, d) * dw).sum() == pytest.approx(1.0, abs=0.005), (k, j)
    assert (table[..., 2] >= 0.0).all() and (table[..., 2] <= 1.0).all()
    rough = table[8:, :, 2]
    assert (rough[:, 1] >= rough[:, -1]).all()  # brighter at grazing
    assert (np.diff(table[8:, -1, 2]) >= -1e-3).all()  # and with roughness, seen from above


def test_the_sheen_is_not_reciprocal_as_cycles_is_not(penumbra):
    """Swapping the view and the light changes the sheen's f (the transformed cosine is fitted
    per view, as Cycles' is): each direction matches the numpy lobe within 2 %."""
    a, b = 40.0, 75.0
    for view, other in ((a, b), (b, a)):
        v, to_light = _directions(view, 90.0 - other)
        ours = _plane(lambda: _material(0.0, 0.5), view, 90.0 - other, samples=1)
        ref = SUN * analytic.sheen_reflectance(0.5, v, to_light)
        assert np.allclose(ours, ref, rtol=0.02), (view, ours, ref)
    v, w = _directions(a, 90.0 - b)
    f_forward = analytic.sheen_reflectance(0.5, v, w) / w[2]
    f_backward = analytic.sheen_reflectance(0.5, w, v) / v[2]
    assert abs(f_forward - f_backward) > 0.02 * f_forward


def test_sheen_weight_zero_is_the_surface_without_a_sheen(penumbra, gpu_call):
    """Sheen Weight 0: the same image bit for bit as a Principled BSDF never given a sheen, with
    no sheen in its program (no NODE_SHEEN variant); above 0 the variant has it."""
    off = {"Sheen Roughness": 0.2, "Sheen Tint": (0.2, 0.5, 0.9, 1.0)}  # inputs of a sheen of weight 0
    (plain, zero, sheened), compiled = group_off_and_on(gpu_call, off, {"Sheen Weight": 1.0}, "NODE_SHEEN")
    assert np.array_equal(plain, zero) and compiled == [False, True]
    assert not np.array_equal(plain, sheened)


def test_a_linked_sheen_and_a_mix_of_sheens(penumbra):
    """Sheen Weight from a node (a Value of 0.5) is half the sheen of weight 1 under a sun (the
    black base reflects nothing else), and a Mix Shader of a sheen and a black surface without
    one, half-half, is half the sheen too: each within 2 %."""
    view, elevation = 70, 30
    full = _plane(lambda: _material(0.0, 0.6), view, elevation, samples=1)

    def linked():
        mat = _material(0.0, 0.6)
        tree = mat.node_tree
        value = tree.nodes.new("ShaderNodeValue")
        value.outputs[0].default_value = 0.5
        tree.links.new(value.outputs[0], tree.nodes["Principled BSDF"].inputs["Sheen Weight"])
        return mat

    def mixed():
        mat = _material(0.0, 0.6)
        black = {"Base Color": (0.0, 0.0, 0.0, 1.0), "Specular IOR Level": 0.0}
        scenes.mix_with(mat, "ShaderNodeBsdfPrincipled", 0.5, black)
        return mat

    assert full.mean() > 1e-3
    for make in (linked, mixed):
        ours = _plane(make, view, elevation, samples=1)
        assert np.allclose(ours, 0.5 * full, rtol=0.02), (make.__name__, ours, full)


@pytest.mark.parametrize(("sheen_rough", "view", "weight"), [(0.0, 89.5, 1.0), (1.0, 0.0, 1e4), (0.02, 88.0, 1.0)])
def test_the_sheens_extremes(penumbra, sheen_rough, view, weight):
    """Roughness 0 at a grazing view, a view along the normal with a weight of 1e4 (bounded at
    1e3), a near-mirror roughness: every pixel finite and >= 0 (the harness checks it), and the
    value the numpy lobe gives within 5 % (or 1e-4 where it is dark)."""
    elevation = 30
    v, to_light = _directions(view, elevation)
    ref = SUN * min(weight, 1e3) * analytic.sheen_reflectance(sheen_rough, v, to_light)
    ours = _plane(lambda: _material(0.0, sheen_rough, weight=weight), view, elevation, samples=1)
    assert np.isfinite(ours).all()
    assert np.allclose(ours, ref, rtol=0.05, atol=1e-4), (ours, ref)


def test_a_sheen_bsdf_lies_beside_what_it_is_mixed_with(penumbra):
    """A Sheen BSDF (Microfiber) of a colour is that colour x the lobe (within 2 %); mixed
    half-half with a Diffuse BSDF it adds to half the diffuse's light without taking from it
    (Cycles sums closures; only the Principled BSDF layers its sheen), within 2 %."""
    view, elevation = 70, 35
    v, to_light = _directions(view, elevation)
    color = np.array([0.9, 0.5, 0.2])
    sheen = SUN * color * analytic.sheen_reflectance(0.4, v, to_light)
    diffuse = SUN * 0.5 * to_light[2] / math.pi

    def make(mixed):
        def build():
            mat = scenes.material("Velvet", (0.5, 0.5, 0.5))
            tree = mat.node_tree
            node = tree.nodes.new("ShaderNodeBsdfSheen")
            node.distribution = "MICROFIBER"
            node.inputs["Color"].default_value = (*color, 1.0)
            node.inputs["Roughness"].default_value = 0.4
            out = tree.nodes["Material Output"]
            if mixed:
                dif = tree.nodes.new("ShaderNodeBsdfDiffuse")
                dif.inputs["Color"].default_value = (0.5, 0.5, 0.5, 1.0)
                mix = tree.nodes.new("ShaderNodeMixShader")
                mix.inputs["Fac"].default_value = 0.5
                tree.links.new(dif.outputs[0], mix.inputs[1])
                tree.links.new(node.outputs[0], mix.inputs[2])
                tree.links.new(mix.outputs[0], out.inputs["Surface"])
            else:
                tree.links.new(node.outputs[0], out.inputs["Surface"])
            return mat

        return build

    alone = _plane(make(False), view, elevation, samples=1)
    assert np.allclose(alone, sheen, rtol=0.02), (alone, sheen)
    mixed = _plane(make(True), view, elevation, samples=1)
    assert np.allclose(mixed, 0.5 * (sheen + diffuse), rtol=0.02), (mixed, sheen, diffuse)


def test_the_sheen_and_coat_light_views_show_their_layer_alone(penumbra, gpu_call):
    """Debug views Sheen Light and Coat Light: over a red diffuse under a sun, each is its
    layer's own light (the numpy lobe's: the sheen within 2 %, the coat within 3 %), not the
    frame's; over a black base without specular the sheen's view is the whole frame; a
    surface without the layer shows black."""
    view, elevation = 70, 35
    v, to_light = _directions(view, elevation)

    def red(sheen=True, coat=False):
        def make():
            mat = _material(0.0, 0.5, weight=1.0 if sheen else 0.0)
            bsdf = mat.node_tree.nodes["Principled BSDF"]
            bsdf.inputs["Base Color"].default_value = (0.6, 0.1, 0.05, 1.0)
            if coat:
                bsdf.inputs["Coat Weight"].default_value = 1.0
                bsdf.inputs["Coat Roughness"].default_value = 0.3
            return mat

        return make

    scene = _plane_scene(red(), view, elevation)
    shown = debug_view_mean(scene, "SHEEN_LIGHT")
    assert np.allclose(shown, SUN * analytic.sheen_reflectance(0.5, v, to_light), rtol=0.02), shown
    assert debug_view_mean(scene, "NONE")[0] > 1.5 * shown[0]
    assert debug_view_mean(scene, "COAT_LIGHT").max() == 0.0
    scene = _plane_scene(lambda: _material(0.0, 0.5), view, elevation)
    np.testing.assert_allclose(debug_view_mean(scene, "SHEEN_LIGHT"), debug_view_mean(scene, "NONE"), rtol=1e-4)
    scene = _plane_scene(red(sheen=False, coat=True), view, elevation)
    shown = debug_view_mean(scene, "COAT_LIGHT")
    gain = analytic.ggx_ms_gain(0.04, 1.0, 0.3, v[2])
    ref = SUN * analytic.coat_reflectance(1.0, 0.3, v, to_light) * gain
    assert ref > 1e-3 and np.allclose(shown, ref, rtol=0.03), (shown, ref)
    assert debug_view_mean(scene, "SHEEN_LIGHT").max() == 0.0
