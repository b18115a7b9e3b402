"""Reflections of the scene in glossy lobes (issue 50; ``engine/frame/features/reflections.py``,
``shaders/lib/ssr.glsl``): screen-space rays traced from the second sample of a frame on, each
hit reading the frame's image so far.

Checked against geometry: a mirror floor under an emissive panel standing on it, in a black
world with no lamp, shows the panel where the panel mirrored about the floor's plane projects
(the mirrored camera's picture, rendered as that mirrored panel alone), at the panel's
radiance times the samples that traced (the first has no image yet). Against Cycles on
``devkit.reflection_scenes`` in ``test_world_env.py``; the cost where nothing is glossy here.
"""

import numpy as np

from devkit import scenes
from devkit.analytic import erode as _erode
from devkit.render import technique_frame

SIZE = (160, 90)
SAMPLES = 16
EMISSION = 2.0
PANEL = dict(size=(2.4, 0.08, 1.0))


# The screen's rays alone: the cube maps (``features/cubes.py``) also find what the screen
# misses, from the frame's first sample on (``tests/shadows/test_cubes.py``).
SCREEN_ONLY = ("cubes",)


def _render(gpu_call, scene, samples=SAMPLES, without=()):
    """(linear RGBA, stats, the samples' filter weights) of a frame of ``scene``, the
    techniques named in ``without`` left out."""
    return technique_frame(gpu_call, scene, *SIZE, samples, without)


def _panel_scene(mirror=True, panel_z=1.0, roughness=0.0):
    """A black world, no lamp; an emissive panel facing the camera at height ``panel_z``
    (its centre; ``-panel_z``: the panel mirrored about z = 0) and with ``mirror`` a white
    metal floor of ``roughness`` at z = 0."""
    scene = scenes.empty_scene(*SIZE)
    scenes.set_world(scene, (0.0, 0.0, 0.0))
    if mirror:
        scenes.plane(scene, "Floor", size=60.0, mat=scenes.material("Mirror", (1.0, 1.0, 1.0), roughness, metallic=1.0))
    scenes.box(scene, "Panel", center=(0.0, 0.0, panel_z), mat=scenes.emissive("Glow", EMISSION), **PANEL)
    scenes.look_at(scene, (0.0, -7.0, 1.1), (0.0, 0.0, 0.1), lens=40.0)
    return scene


def test_a_mirror_floor_shows_the_panel_where_the_mirrored_camera_sees_it(penumbra, gpu_call):
    """Where the mirrored panel projects (less the panel itself and a pixel of edge), the
    floor holds the panel's radiance times the share of the frame's filter weight its traced
    samples carry (all but the first; within -8 % and +2 %: the metal's Fresnel at white is 1;
    measured 1.000); where nothing is reflected it stays black (the 99th percentile below 2 %
    of it; measured 0, 0.85 before rays that graze their own floor were told from hits), and
    the reflection's outline is the mirrored panel's (intersection over union at least 0.85;
    measured 0.91, the edge pixels)."""
    image, stats, weights = _render(gpu_call, _panel_scene(), without=SCREEN_ONLY)
    mirrored, _s, _w = _render(gpu_call, _panel_scene(mirror=False, panel_z=-1.0))
    panel, _s, _w = _render(gpu_call, _panel_scene(mirror=False))
    assert "reflections" in stats.techniques and stats.reflection_prepasses == 1
    assert stats.reflection_samples == SAMPLES - 1
    lum = image[..., :3].mean(axis=2)
    seen = panel[..., :3].mean(axis=2) > 0.5 * EMISSION
    where = (mirrored[..., :3].mean(axis=2) > 0.5 * EMISSION) & ~seen
    traced = 1.0 - weights[0] / sum(weights)
    inside = _erode(where, 1)
    assert inside.sum() > 100, inside.sum()
    ratio = float(np.median(lum[inside])) / (EMISSION * traced)
    assert 0.92 <= ratio <= 1.02, (ratio, traced)
    dark = _erode(~(where | seen), 2)
    assert float(np.percentile(lum[dark], 99)) <= 0.02 * EMISSION
    reflected = (lum > 0.5 * EMISSION * traced) & ~seen
    iou = (reflected & where).sum() / (reflected | where).sum()
    assert iou >= 0.85, iou


def test_nothing_glossy_costs_nothing(penumbra, gpu_call):
    """A rough floor (roughness 0.6: the ratio shadows all of its specular) takes no
    reflections: no technique, no prepass, no traced sample; nor a one-sample frame of the
    mirror floor."""
    _image, stats, _w = _render(gpu_call, _panel_scene(roughness=0.6))
    assert "reflections" not in stats.techniques and stats.reflection_prepasses == 0
    _image, stats, _w = _render(gpu_call, _panel_scene(), samples=1)
    assert "reflections" not in stats.techniques and stats.reflection_samples == 0


def test_a_rough_floor_blurs_the_reflection(penumbra, gpu_call):
    """A floor of roughness 0.3 blurs the panel's reflection: its peak is lower than the
    mirror's, it spreads over more of the floor (pixels above a twentieth of the panel's
    radiance), and it stays finite and non-negative."""
    mirror, _s, _w = _render(gpu_call, _panel_scene())
    rough, stats, _w = _render(gpu_call, _panel_scene(roughness=0.3))
    assert "reflections" in stats.techniques
    panel, _s, _w = _render(gpu_call, _panel_scene(mirror=False))
    seen = panel[..., :3].mean(axis=2) > 0.5 * EMISSION
    below = np.zeros_like(seen)
    below[: np.nonzero(seen.any(axis=1))[0].min() - 1] = True
    a, b = mirror[..., :3].mean(axis=2)[below], rough[..., :3].mean(axis=2)[below]
    assert np.isfinite(b).all() and (b >= 0).all()
    spread = ((b > 0.05 * EMISSION).sum(), (a > 0.05 * EMISSION).sum())
    assert b.max() < 0.95 * a.max() and spread[0] > 1.1 * spread[1], (b.max(), a.max(), spread)


def test_screen_space_reflections_off_traces_nothing(penumbra, gpu_call):
    """Render Properties › Light Paths › Screen Space Reflections off: the mirror floor takes
    no reflections (no technique, no prepass) and shows only the world's light, black here."""
    scene = _panel_scene()
    scene.penumbra.screen_space_reflections = False
    image, stats, _w = _render(gpu_call, scene)
    assert "reflections" not in stats.techniques and stats.reflection_prepasses == 0
    panel, _s, _w = _render(gpu_call, _panel_scene(mirror=False))
    # (Two pixels from the panel: the pixel filter spreads its edge.)
    away = _erode(~(panel[..., :3].mean(axis=2) > 0.01), 2)
    assert float(image[..., :3][away].max()) <= 1e-6


def test_the_viewport_drawing_a_sample_a_call_shows_the_final_render(penumbra, gpu_call):
    """The viewport draws a frame's samples one call at a time: the reflections' prepass is
    drawn once for the frame (at the pixels' centres, not at the pixel offset of the call
    that first traces), so after n calls the mirror floor is the n-sample final render's,
    exactly (the same pixels: the rays and their hits are the same)."""
    from devkit.render import render, viewport_calls

    scene = _panel_scene()
    scene.penumbra.render_samples = scene.penumbra.viewport_samples = 6
    scene.penumbra.preview_adaptive_threshold = scene.penumbra.adaptive_threshold
    final = render(scene)["Combined"]

    image, calls = viewport_calls(gpu_call, scene, *SIZE, 6)
    prepasses, traced = sum(s.reflection_prepasses for s in calls), sum(s.reflection_samples for s in calls)
    assert prepasses == 1 and traced == 5
    assert float(final[..., :3].max()) > EMISSION * 0.5  # the reflection is there
    np.testing.assert_array_equal(image, final)


def test_the_reflections_view_shows_where_the_rays_met_the_scene(penumbra, gpu_call):
    """Debug view REFLECTIONS: every sample traces, and the view's values are the share of the
    samples whose ray met the scene. On the mirror floor that is 1 where the mirrored panel
    projects (the outline's IoU with it at least 0.85; measured 0.91) and 0 where the floor
    reflects the world (away from the panel: a ray that leaves the screen); a rough floor
    traces nothing, 0 everywhere."""
    from penumbra.engine.frame.features import REGISTRY
    from penumbra.engine.frame.renderer import Renderer
    from penumbra.engine.scene.extract import camera_from_scene

    def view(scene):
        scene.penumbra.debug_view = "REFLECTIONS"

        def job(engine, depsgraph):
            engine.renderer = Renderer(features=tuple(f for f in REGISTRY if f.name not in SCREEN_ONLY))
            cam = camera_from_scene(depsgraph, scene, *SIZE)
            out = engine.render_frame(depsgraph, cam, *SIZE, samples=(0, 8), sample_count=8)
            return out.debug.values.copy(), out.stats

        return gpu_call(job)

    values, stats = view(_panel_scene())
    assert stats.reflection_samples == 8 and "REFLECTIONS" in stats.debug_legend.upper()
    mirrored, _s, _w = _render(gpu_call, _panel_scene(mirror=False, panel_z=-1.0))
    panel, _s, _w = _render(gpu_call, _panel_scene(mirror=False))
    seen = panel[..., :3].mean(axis=2) > 0.5 * EMISSION
    where = (mirrored[..., :3].mean(axis=2) > 0.5 * EMISSION) & ~seen
    met = values > 0.5
    iou = (met & where).sum() / (met | where).sum()
    assert iou >= 0.85, iou
    # Within it every ray meets the panel, but along the panel's top edge, which steps of a
    # ray that crosses it near-parallel pass over in some samples (measured: all at 3 pixels
    # in, 92 % of the pixels at 1 pixel in).
    inside = values[_erode(where, 1)]
    assert float(values[_erode(where, 3)].min()) >= 0.99 and np.mean(inside >= 0.99) >= 0.85
    far = _erode(~(where | seen), 3)
    assert float(values[far].max()) <= 0.01  # (measured 0.001: a hit faded out at the screen's edge)
    rough, stats = view(_panel_scene(roughness=0.6))
    assert stats.reflection_samples == 0 and float(np.abs(rough).max()) == 0.0
