"""Motion blur by sampling the shutter (engine/frame/motion.py), rendered, against the
motion's geometry: a small emitting sphere against a black world moving across a 50 mm
camera's view at a known speed (pixel filter 0: each sample looks through the pixel's
centre)."""

import math

import numpy as np
import pytest

from devkit import scenes
from devkit.render import render

W, H = 128, 64
RHO = 0.05
DEPTH = 4.0
SAMPLES = 64


def _scene(shutter=0.5, blur=True, samples=SAMPLES, interpolation="LINEAR", camera_moves=False):
    """The sphere at x = -1 on frame 1 and x = +1 on frame 3 (or the camera moving the other
    way), rendered at frame 2."""
    scene = scenes.empty_scene(W, H)
    mat = scenes.emissive()
    ball = scenes.uv_sphere(scene, "Ball", center=(0.0, 0.0, -DEPTH), radius=RHO, segments=64, rings=32, mat=mat)
    cam = scenes.camera(scene, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), lens=50.0, clip=(0.1, 100.0))
    cam.data.sensor_fit = "HORIZONTAL"
    moving, sign = (cam, -1.0) if camera_moves else (ball, 1.0)
    for frame, x in ((1, -1.0), (3, 1.0)):
        moving.location.x = sign * x
        moving.keyframe_insert("location", index=0, frame=frame)
    for fc in _fcurves(moving):
        for point in fc.keyframe_points:
            point.interpolation = interpolation
    scene.frame_set(2)
    scene.render.use_motion_blur = blur
    scene.render.motion_blur_shutter = shutter
    scene.render.motion_blur_position = "CENTER"
    scene.penumbra.filter_size = 0.0
    scene.penumbra.render_samples = samples
    scene.penumbra.use_adaptive_sampling = False
    return scene


def _fcurves(ob):
    action = ob.animation_data.action
    if hasattr(action, "fcurves") and len(action.fcurves):
        return list(action.fcurves)
    return [fc for layer in action.layers for strip in layer.strips for bag in strip.channelbags for fc in bag.fcurves]


def _k():
    return 2.0 * 50.0 / 36.0 * 0.5 * W


def _simulated(shutter, samples):
    """The image the motion predicts, sampled as the film samples it: at each sample's time in
    the shutter (``motion.sample_time``) the sphere at x = 2 shutter (u - 1/2) (one unit a
    frame), its silhouette's pixel centres."""
    from penumbra.engine.frame.motion import sample_time

    k = _k()
    r = k * RHO / math.sqrt(DEPTH**2 - RHO**2)
    x, y = np.meshgrid(np.arange(W) + 0.5, np.arange(H) + 0.5)
    image = np.zeros((H, W))
    for s in range(samples):
        u = sample_time(s, samples)
        cx = W / 2 + k * shutter * (u - 0.5) / DEPTH  # one world unit a frame
        image += (x - cx) ** 2 + (y - H / 2) ** 2 <= r * r
    return image / samples


def _moments(image):
    y, x = np.mgrid[0:H, 0:W] + 0.5
    w = image / image.sum()
    cx, cy = (w * x).sum(), (w * y).sum()
    return cx, cy, (w * (x - cx) ** 2).sum(), (w * (y - cy) ** 2).sum()


@pytest.mark.parametrize("camera_moves", [False, True])
def test_a_moving_object_smears_over_the_shutters_length(penumbra, camera_moves):
    """At one world unit a frame and a shutter of half a frame, the sphere's image smears over
    half a unit (22.2 pixels) centred where it is at the frame's time: its second moment along
    the motion that of the simulated shutter within half a pixel of length, its height and
    light unchanged; the same when the camera moves the other way instead."""
    image = render(_scene(camera_moves=camera_moves))["Combined"][..., 0].astype(np.float64)
    expected = _simulated(0.5, SAMPLES)
    got, want = _moments(image), _moments(expected)
    assert got[0] == pytest.approx(want[0], abs=0.25) and got[1] == pytest.approx(want[1], abs=0.25)
    assert math.sqrt(12.0 * got[2]) == pytest.approx(math.sqrt(12.0 * want[2]), abs=0.5)
    assert math.sqrt(12.0 * want[2]) > 0.9 * 0.5 * _k() / DEPTH  # a segment of length L has L^2 / 12
    assert got[3] == pytest.approx(want[3], abs=0.1)
    cols = np.flatnonzero((image > 0.5 / SAMPLES).any(axis=0))
    assert abs(len(cols) - np.flatnonzero((expected > 0).any(axis=0)).size) <= 1
    assert image.sum() == pytest.approx(expected.sum(), rel=0.05)


def test_a_shutter_of_zero_is_the_unblurred_image(penumbra):
    still = render(_scene(blur=False))["Combined"]
    zero = render(_scene(shutter=0.0))["Combined"]
    assert np.array_equal(still, zero)
    assert still[..., 0].sum() > 5.0


@pytest.mark.parametrize("case", ["shutter 2", "teleport", "one sample"])
def test_extreme_shutters_stay_finite(penumbra, case):
    """A shutter of two frames, an object jumping between frames (constant interpolation), one
    sample: finite images (the harness checks every render), two frames twice the smear, the
    jump a sphere at each end, one sample the frame's own image."""
    scene = _scene(
        shutter=2.0 if case == "shutter 2" else 0.5,
        interpolation="CONSTANT" if case == "teleport" else "LINEAR",
        samples=1 if case == "one sample" else 32,
    )
    image = render(scene)["Combined"][..., 0]
    assert np.all(np.isfinite(image))
    if case == "shutter 2":
        lit = np.flatnonzero((image > 0.5 / 32).any(axis=0))
        assert lit.max() - lit.min() > 1.8 * 0.5 * _k() / DEPTH * 2.0
    if case == "one sample":
        still = render(_scene(blur=False, samples=1))["Combined"][..., 0]
        assert np.array_equal(image, still)


def test_the_shutters_steps_are_read_once_with_what_deforms(penumbra, gpu_call):
    """Render > Motion Blur is read at the shutter's start, centre and end (the frame set back
    after): only what moves is kept, the camera when it moves, the shutter curve where it is
    not flat; a mesh whose shape changes over the shutter (an animated shape key) is kept with
    its vertices at each step, one whose modifier deforms it alike at every step is not, and a
    deformed one whose topology changes (an animated Build modifier) is named once."""
    scene = _scene()
    cube = scenes.box(scene, "Wobbly", center=(0.0, 1.0, -6.0), size=(0.3, 0.3, 0.3))
    cube.modifiers.new("Twist", "SIMPLE_DEFORM")
    morph = scenes.box(scene, "Morph", center=(0.0, -1.0, -6.0), size=(0.3, 0.3, 0.3))
    morph.shape_key_add(name="Basis")
    key = morph.shape_key_add(name="Up")
    for v in key.data:
        v.co.z += 0.5
    for frame, value in ((1, 0.0), (3, 1.0)):
        key.value = value
        key.keyframe_insert("value", frame=frame)
    for fc in _fcurves(morph.data.shape_keys):
        for point in fc.keyframe_points:
            point.interpolation = "LINEAR"
    growing = scenes.uv_sphere(scene, "Growing", center=(1.0, 0.0, -6.0), radius=0.2)
    build = growing.modifiers.new("Build", "BUILD")
    build.frame_start, build.frame_duration = 1, 3
    growing.modifiers.new("Bend", "SIMPLE_DEFORM")  # deformed, and its faces appear over the frames
    curve = scene.render.motion_blur_shutter_curve
    curve.curves[0].points[0].location = (0.0, 0.2)
    curve.update()

    def job(engine, depsgraph):
        motion, messages = engine.read_motion(depsgraph)
        return motion, messages, depsgraph.scene.frame_current, depsgraph.scene.frame_subframe

    motion, messages, frame, subframe = gpu_call(job)
    assert (frame, subframe) == (2, 0.0)
    assert motion is not None and motion.times == (0.0, 0.5, 1.0)
    assert set(motion.instances) == {("Ball",)}
    xs = [m[0, 3] for m in motion.instances[("Ball",)]]
    np.testing.assert_allclose(xs, [-0.25, 0.0, 0.25], atol=1e-6)
    assert motion.camera is None and motion.curve is not None and motion.curve[0] < motion.curve[-1]
    assert set(motion.shapes) == {("Morph",)}
    zs = [float(shape.positions[:, 2].max()) for shape in motion.shapes[("Morph",)]]
    np.testing.assert_allclose(np.diff(zs), [0.0625, 0.0625], atol=1e-5)  # 0.5 a unit of value, 0.25 a step
    assert len(messages) == 1 and "'Growing'" in messages[0] and "topology" in messages[0]
    scene.render.use_motion_blur = False
    assert gpu_call(job)[0] is None


@pytest.mark.parametrize("how", ["shape key", "armature"])
def test_a_deforming_mesh_smears_as_the_same_motion_by_its_transform(penumbra, how):
    """The sphere moved by its vertices (a shape key's value, an armature's bone) instead of its
    object: each sample draws its vertices where they are at its time, so the image is the one
    the same motion by the object's transform gives (the simulated shutter's within half a
    pixel)."""
    import bpy

    moved = render(_scene())["Combined"][..., 0].astype(np.float64)
    scene = _scene()
    ball = bpy.data.objects["Ball"]
    ball.animation_data_clear()
    ball.location.x = 0.0
    if how == "shape key":
        ball.shape_key_add(name="Basis")
        key = ball.shape_key_add(name="Across")
        key.slider_min = -1.0
        for v in key.data:
            v.co.x += 1.0
        for frame, value in ((1, -1.0), (3, 1.0)):
            key.value = value
            key.keyframe_insert("value", frame=frame)
        owner = ball.data.shape_keys
    else:
        arm = bpy.data.objects.new("Rig", bpy.data.armatures.new("Rig"))
        scene.collection.objects.link(arm)
        bpy.context.view_layer.objects.active = arm
        bpy.ops.object.mode_set(mode="EDIT")
        bone = arm.data.edit_bones.new("Bone")
        bone.head, bone.tail = (0.0, 0.0, -DEPTH), (0.0, 0.0, -DEPTH + 0.5)
        bpy.ops.object.mode_set(mode="OBJECT")
        ball.parent = arm
        ball.modifiers.new("Armature", "ARMATURE").object = arm
        group = ball.vertex_groups.new(name="Bone")
        group.add(list(range(len(ball.data.vertices))), 1.0, "REPLACE")
        pose = arm.pose.bones["Bone"]
        for frame, x in ((1, -1.0), (3, 1.0)):
            pose.matrix = _bone_at(arm, x)
            pose.keyframe_insert("location", frame=frame)
        owner = arm
    for fc in _fcurves(owner):
        for point in fc.keyframe_points:
            point.interpolation = "LINEAR"
    scene.frame_set(2)
    deformed = render(scene)["Combined"][..., 0].astype(np.float64)
    assert np.abs(moved - deformed).max() < 1e-3
    got, want = _moments(deformed), _moments(_simulated(0.5, SAMPLES))
    assert math.sqrt(12.0 * got[2]) == pytest.approx(math.sqrt(12.0 * want[2]), abs=0.5)


def _bone_at(arm, x):
    """The pose matrix (armature space) that moves the bone ``x`` along world x."""
    from mathutils import Matrix

    rest = arm.data.bones["Bone"].matrix_local
    return Matrix.Translation((x, 0.0, 0.0)) @ rest


@pytest.mark.parametrize("steps", [1, 2, 64])
def test_motion_steps_are_cycles_and_an_object_can_opt_out(penumbra, gpu_call, steps):
    """Cycles' Object > Motion Blur > Steps n reads 2^n + 1 times (3, 5, and at 64 Cycles'
    most, 129), evenly over the shutter; an object with its Motion Blur off does not blur."""
    from penumbra.engine.render_engine import MAX_MOTION_STEPS

    scene = _scene()
    ball = scene.objects["Ball"]
    ball.cycles.motion_steps = steps

    def job(engine, depsgraph):
        return engine.read_motion(depsgraph)[0]

    motion = gpu_call(job)
    count = min(2**steps + 1, MAX_MOTION_STEPS)
    assert len(motion.times) == count and motion.times[0] == 0.0 and motion.times[-1] == 1.0
    xs = [m[0, 3] for m in motion.instances[("Ball",)]]
    np.testing.assert_allclose(xs, np.linspace(-0.25, 0.25, count), atol=1e-6)
    if steps == 1:
        ball.cycles.use_motion_blur = False
        assert gpu_call(job) is None
