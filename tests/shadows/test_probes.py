"""What the screen does not hold (issue 50): planar reflections from Plane Light Probes
(``engine/frame/features/planar.py``, ``shaders/lib/planar.glsl``: each sample draws the
scene mirrored about the probe's plane, and traced lobes in the probe's influence read that
capture), and cube maps (``features/cubes.py``, ``shaders/lib/cubes.glsl``: a Sphere Light
Probe's and the camera's, drawn once a frame, marched by the rays the rest leave).

Checked against geometry: a mirror floor with a Plane probe, in a black world with no lamp,
shows an emissive panel that hangs above the camera's view (off the screen, where no
screen-space ray can find it) where the panel mirrored about the floor's plane projects (the
mirrored camera's picture, rendered as that mirrored panel alone), at the panel's radiance
in every sample, the first and a one-sample frame's too. What the probe's square does not
cover and what it costs where nothing needs it are checked beside. The same panel is found
by the camera's cube map, and by a Sphere probe's in its influence.
"""

import numpy as np
import pytest

from devkit import scenes
from devkit.analytic import erode as _erode
from devkit.render import technique_frame

SIZE = (160, 90)
SAMPLES = 8
EMISSION = 2.0
# A panel above the top of the camera's view: seen only in the mirror.
PANEL = dict(center=(0.0, 1.0, 2.6), size=(2.4, 0.08, 1.0))
CAMERA = ((0.0, -7.0, 1.1), (0.0, 0.0, -0.6))


# What the screen holds alone: the camera's cube map (``features/cubes.py``) finds the panel too.
SCREEN_ONLY = ("cubes",)


def _render(gpu_call, scene, samples=SAMPLES, without=()):
    """(linear RGBA, stats) of a frame of ``scene`` (one sample: the single-sample frame), the
    techniques named in ``without`` left out."""
    image, stats, _weights = technique_frame(gpu_call, scene, *SIZE, samples, without)
    return image, stats


def _scene(mirror=True, probe=True, panel_z=None, roughness=0.0, probe_size=(60.0, 60.0), probe_x=0.0, scale=1.0):
    """A black world, no lamp; an emissive panel facing down the camera's axis above its view
    (``panel_z``: its centre's height, mirrored below the floor where negative), and with
    ``mirror`` a white metal floor of ``roughness`` at z = 0, with ``probe`` a Plane probe on it
    (its square ``probe_size`` across, centred at x = ``probe_x``); every length (the camera's
    clip range too) times ``scale``."""
    s = float(scale)
    scene = scenes.empty_scene(*SIZE)
    scenes.set_world(scene, (0.0, 0.0, 0.0))
    if mirror:
        mat = scenes.material("Mirror", (1.0, 1.0, 1.0), roughness, metallic=1.0)
        scenes.plane(scene, "Floor", size=60.0 * s, mat=mat)
    if probe:
        scenes.plane_probe(
            scene, location=(probe_x * s, 0.0, 0.0), size=(probe_size[0] * s, probe_size[1] * s), distance=0.1 * s
        )
    center = PANEL["center"] if panel_z is None else (*PANEL["center"][:2], panel_z)
    size = PANEL["size"]
    glow = scenes.emissive("Glow", EMISSION)
    scenes.box(scene, "Panel", center=tuple(c * s for c in center), size=tuple(c * s for c in size), mat=glow)
    location, target = CAMERA
    cam = scenes.look_at(scene, tuple(c * s for c in location), tuple(c * s for c in target), lens=40.0)
    cam.data.clip_start, cam.data.clip_end = 0.1 * s, 100.0 * s
    return scene


@pytest.fixture(scope="module")
def mirrored_panel(penumbra, gpu_call):
    """Where the panel mirrored about z = 0 projects: the mirrored camera's picture of it."""
    image, _stats = _render(gpu_call, _scene(mirror=False, probe=False, panel_z=-PANEL["center"][2]))
    return image[..., :3].mean(axis=2) > 0.5 * EMISSION


@pytest.mark.parametrize("samples", [1, SAMPLES])
def test_a_mirror_probe_shows_what_the_screen_does_not_hold(penumbra, gpu_call, mirrored_panel, samples):
    """The panel is off the screen (the camera alone sees none of it); with a Plane probe on
    the mirror floor the floor holds the panel's radiance where the mirrored panel projects
    (its median within -3 % and +2 %: a white metal's Fresnel is 1; every sample, the first
    too), black elsewhere (99th percentile under 2 % of it), and the reflection's outline is
    the mirrored panel's (intersection over union at least 0.85). Without the probe the
    screen's reflections cannot find the panel (the camera's cube map left out too): the
    floor stays black."""
    panel, _s = _render(gpu_call, _scene(mirror=False, probe=False), samples=1)
    assert float(panel[..., :3].max()) <= 1e-6, "the panel must be off the screen"
    where = mirrored_panel
    inside = _erode(where, 1)
    assert inside.sum() > 100, inside.sum()
    image, stats = _render(gpu_call, _scene(), samples=samples)
    assert "planar" in stats.techniques and stats.planar_captures == samples
    lum = image[..., :3].mean(axis=2)
    ratio = float(np.median(lum[inside])) / EMISSION
    assert 0.97 <= ratio <= 1.02, ratio
    dark = _erode(~where, 2)
    assert float(np.percentile(lum[dark], 99)) <= 0.02 * EMISSION
    reflected = lum > 0.5 * EMISSION
    iou = (reflected & where).sum() / (reflected | where).sum()
    assert iou >= 0.85, iou
    without, stats = _render(gpu_call, _scene(probe=False), samples=samples, without=SCREEN_ONLY)
    assert "planar" not in stats.techniques and stats.planar_captures == 0
    assert float(without[..., :3].mean(axis=2)[inside].max()) <= 0.02 * EMISSION


def test_the_probe_square_bounds_its_influence(penumbra, gpu_call, mirrored_panel):
    """A probe whose square covers only the floor left of x = 0 reflects the panel there and
    nowhere right of it (beyond a pixel's filter)."""
    image, stats = _render(gpu_call, _scene(probe_size=(30.0, 60.0), probe_x=-15.0), samples=1)
    lum = image[..., :3].mean(axis=2)
    inside = _erode(mirrored_panel, 1)
    middle = SIZE[0] // 2
    left, right = inside.copy(), inside.copy()
    left[:, middle - 2 :] = False
    right[:, : middle + 2] = False
    assert left.sum() > 30 and right.sum() > 30
    assert float(np.median(lum[left])) >= 0.97 * EMISSION
    assert float(lum[right].max()) <= 0.02 * EMISSION


def test_a_rough_probe_floor_blurs_the_reflection(penumbra, gpu_call, mirrored_panel):
    """A floor of roughness 0.3 under the probe spreads the panel's reflection: a lower peak
    than the mirror's over more of the floor, finite and non-negative."""
    mirror, _s = _render(gpu_call, _scene())
    rough, stats = _render(gpu_call, _scene(roughness=0.3))
    assert "planar" in stats.techniques
    a, b = mirror[..., :3].mean(axis=2), rough[..., :3].mean(axis=2)
    assert np.isfinite(b).all() and (b >= 0).all()
    spread = ((b > 0.05 * EMISSION).sum(), (a > 0.05 * EMISSION).sum())
    assert b.max() < 0.95 * a.max() and spread[0] > 1.1 * spread[1], (b.max(), a.max(), spread)


def test_a_probe_costs_nothing_where_nothing_needs_it(penumbra, gpu_call):
    """No capture where the floor is rough (0.6: no traced lobe), nor where the probe's mirror
    is out of view (under the camera, facing away), nor without the technique; the draw
    calls are then those of the scene without a probe."""
    _image, bare = _render(gpu_call, _scene(probe=False, roughness=0.6), samples=2)
    _image, stats = _render(gpu_call, _scene(roughness=0.6), samples=2)
    assert "planar" not in stats.techniques and stats.planar_captures == 0
    assert (stats.draws, stats.passes) == (bare.draws, bare.passes)
    scene = _scene()
    probe = scene.objects["Mirror Probe"]
    probe.rotation_euler = (np.pi, 0.0, 0.0)  # its mirror faces down, away from the camera
    _image, stats = _render(gpu_call, scene, samples=2)
    assert stats.planar_captures == 0
    _image, stats = _render(gpu_call, _scene(), samples=2, without=("planar",))
    assert stats.planar_captures == 0


@pytest.mark.parametrize("scale", [1e-3, 1e3])
def test_a_mirror_probe_at_millimetre_and_kilometre_scales(penumbra, gpu_call, mirrored_panel, scale):
    """The same mirror, panel and camera a thousand times smaller and larger: the reflection
    lies where it does at 1 (outline IoU at least 0.85 against the mirrored panel at scale 1)
    at the panel's radiance (median within -3 % and +2 %)."""
    image, stats = _render(gpu_call, _scene(scale=scale), samples=1)
    assert stats.planar_captures == 1
    lum = image[..., :3].mean(axis=2)
    inside = _erode(mirrored_panel, 1)
    ratio = float(np.median(lum[inside])) / EMISSION
    assert 0.97 <= ratio <= 1.02, ratio
    reflected = lum > 0.5 * EMISSION
    iou = (reflected & mirrored_panel).sum() / (reflected | mirrored_panel).sum()
    assert iou >= 0.85, iou


def test_degenerate_probes_and_a_grazing_camera(penumbra, gpu_call):
    """A probe of zero size draws no capture; a camera a millimetre over the mirror, looking
    along it, renders a finite, non-negative frame with its capture."""
    scene = _scene()
    scene.objects["Mirror Probe"].scale = (0.0, 0.0, 1.0)
    image, stats = _render(gpu_call, scene, samples=1)
    assert stats.planar_captures == 0 and np.isfinite(image).all()
    scene = _scene()
    scenes.look_at(scene, (0.0, -7.0, 1e-3), (0.0, 10.0, 1e-3), lens=40.0)
    image, stats = _render(gpu_call, scene, samples=2)
    assert stats.planar_captures == 2
    assert np.isfinite(image).all() and (image[..., :3] >= 0.0).all()


def test_probes_penumbra_does_not_use_are_named(penumbra, gpu_call):
    """A Volume probe is named in the report, once; of two Plane probes in view the frame
    reflects one and names the other."""
    import bpy

    scene = _scene()
    for kind in ("VOLUME",):
        ob = bpy.data.objects.new(f"{kind.title()} Probe", bpy.data.lightprobes.new(kind, kind))
        scenes.link(scene, ob)
    scenes.plane_probe(scene, "Second Mirror", location=(0.0, 0.0, 0.0), size=(4.0, 4.0))
    _image, stats = _render(gpu_call, scene, samples=1)
    text = "\n".join(stats.messages)
    assert text.count("Volume Light Probe 'Volume Probe' is not used") == 1, text
    assert text.count("Plane Light Probe 'Second Mirror' is not drawn") == 1, text
    assert stats.planar_captures == 1


def _hit_share(image, where):
    """The median share of the panel's radiance over the eroded ``where``."""
    lum = image[..., :3].mean(axis=2)
    return float(np.median(lum[_erode(where, 1)])) / EMISSION


def test_the_cameras_cube_finds_what_the_screen_does_not_hold(penumbra, gpu_call, mirrored_panel):
    """No probe: the camera's cube map (drawn once a frame at the camera, all around it) holds
    the panel above the view, and the rays that leave the screen find it there: the floor
    shows the panel where the mirrored panel projects (median at least 90 % of its radiance:
    the march's steps miss some samples' rays at its edges), black away from it (99th
    percentile under 2 %), six faces drawn once for the frame."""
    image, stats = _render(gpu_call, _scene(probe=False))
    assert "cubes" in stats.techniques and stats.cube_faces == 6 and stats.planar_captures == 0
    share = _hit_share(image, mirrored_panel)
    assert 0.9 <= share <= 1.02, share
    lum = image[..., :3].mean(axis=2)
    assert float(np.percentile(lum[_erode(~mirrored_panel, 2)], 99)) <= 0.02 * EMISSION


def _sphere_probe(scene, location, radius, name="Room Probe"):
    import bpy

    data = bpy.data.lightprobes.new(name, "SPHERE")
    data.influence_distance = radius
    data.clip_start, data.clip_end = 0.01, 200.0
    ob = bpy.data.objects.new(name, data)
    ob.location = location
    return scenes.link(scene, ob)


def test_a_sphere_probes_cube_reflects_in_its_influence(penumbra, gpu_call, mirrored_panel):
    """Screen Space Reflections off (no screen rays, no camera cube): a Sphere probe over the
    floor whose influence holds it shows the panel where the mirrored panel projects (median
    at least 90 %), through its own cube's depth (the parallax from the probe's point to the
    floor's); a probe whose influence lies away from the floor shows nothing; a second probe
    the camera sees is named."""
    scene = _scene(probe=False)
    scene.penumbra.screen_space_reflections = False
    _sphere_probe(scene, (0.0, -6.0, 0.5), 40.0)
    image, stats = _render(gpu_call, scene)
    assert stats.cube_faces == 6, stats.cube_faces
    assert _hit_share(image, mirrored_panel) >= 0.9
    scene = _scene(probe=False)
    scene.penumbra.screen_space_reflections = False
    _sphere_probe(scene, (2.6, 0.0, 0.3), 0.6)
    _sphere_probe(scene, (-2.6, 0.0, 0.3), 0.6, "Other Probe")
    image, stats = _render(gpu_call, scene)
    assert stats.cube_faces == 6
    assert float(image[..., :3].mean(axis=2)[_erode(mirrored_panel, 1)].max()) <= 0.02 * EMISSION
    assert sum("Sphere Light Probe" in m and "is not drawn" in m for m in stats.messages) == 1


def test_cube_maps_cost_nothing_where_nothing_needs_them(penumbra, gpu_call):
    """No cube is drawn for a one-sample frame, a rough floor, or with Screen Space Reflections
    off and no Sphere probe."""
    _image, stats = _render(gpu_call, _scene(probe=False), samples=1)
    assert stats.cube_faces == 0 and "cubes" not in stats.techniques
    _image, stats = _render(gpu_call, _scene(probe=False, roughness=0.6))
    assert stats.cube_faces == 0
    scene = _scene(probe=False)
    scene.penumbra.screen_space_reflections = False
    _image, stats = _render(gpu_call, scene)
    assert stats.cube_faces == 0


def test_the_viewport_drawing_a_sample_a_call_shows_the_final_render(penumbra, gpu_call):
    """The viewport draws a frame's samples one call at a time: the Plane probe's capture is
    drawn every sample (settling's pilot too), the cube maps once for the frame (its first call) and kept
    over the later calls, so after n calls the frame is the n-sample final render's, exactly."""
    from devkit.render import render, viewport_calls

    scene = _scene()
    _sphere_probe(scene, (0.0, -6.0, 0.5), 40.0)
    scene.penumbra.render_samples = scene.penumbra.viewport_samples = 6
    scene.penumbra.preview_adaptive_threshold = scene.penumbra.adaptive_threshold
    final = render(scene)["Combined"]

    image, calls = viewport_calls(gpu_call, scene, *SIZE, 6)
    captures, faces = sum(s.planar_captures for s in calls), sum(s.cube_faces for s in calls)
    # A capture each sample (and for settling's pilot sample), the two cubes once.
    assert captures in (6, 7) and faces == 12, (captures, faces)
    assert float(final[..., :3].max()) > EMISSION * 0.5  # the reflection is there
    np.testing.assert_array_equal(image, final)
