"""Cube maps of the scene for what the screen does not hold (lib/cubes.glsl): a Sphere Light
Probe's, captured at the probe, and the camera's own, captured at the camera, each drawn once a
frame by the lit pass itself (six 90 deg faces, the frame's first sample's lights, maps and
world) into one atlas of colour and the faces' view depth. A traced lobe's ray that neither a
Plane probe's capture nor the screen met (``planar.py``, ``reflections.py``) is marched
through the cubes, in the probe's influence through the probe's cube first, then through the
camera's: the same ray drawn anew each sample, its points stepped along it and compared with
the depth the cube holds in their direction (a screen-space march in a capture that sees all
around; the parallax comes from the depth, not from a parallax volume). A hit reads the
cube's colour there; a ray neither meets takes the world's light. So a mirror sphere shows the
ground beside and behind it and the objects off the image; a polished floor what stands
behind the camera.

Wanted in frames of several samples (the first sample traces the cubes too: it needs no image
of the frame) whose surfaces may have a traced lobe (``reflective_materials``): the camera's
cube with Screen Space Reflections on (the switch of the scene's reflections), a Sphere
probe's wherever the camera sees its influence. A one-sample frame (the viewport while the
view moves) and a rough scene draw none.

Approximate (docs/design.md, as the screen's reflections, not in the report: a fallback of
theirs): a cube is captured once a frame, with the lights and maps of its first sample (its
soft shadows do not converge in what the cube shows), the lights as the camera's view culled
them and the maps as fitted to it, the world's ratio of that sample's directions; what it
shows reflects the world, not the scene. One Sphere probe a frame (the nearest to the camera
whose influence the camera sees; the others named); its parallax volume and visibility
collection are not read (the depth gives the parallax)."""

import numpy as np

from ....shaders.loader import Program, ProgramPart
from ...gpu_pool import new_texture
from ...scene.extract import Camera
from ...shadows import lightspace
from ..draw_list import longest_ray, reflective_materials
from ..film import Film
from .base import Feature, LitPart, captured_parts

COLOR_SAMPLER = "cube_color"
DEPTH_SAMPLER = "cube_depth"
STEPS = 24
THICKNESS = 0.02  # a surface's thickness, as a fraction of its depth, that a ray behind it still meets

# The six faces: (right, up, forward) of each, +X, -X, +Y, -Y, +Z, -Z; face k's slot in a
# cube's 3 x 2 block of the atlas is (k % 3, k // 3).
FACES = (
    ((0, -1, 0), (0, 0, 1), (1, 0, 0)),
    ((0, 1, 0), (0, 0, 1), (-1, 0, 0)),
    ((1, 0, 0), (0, 0, 1), (0, 1, 0)),
    ((-1, 0, 0), (0, 0, 1), (0, -1, 0)),
    ((1, 0, 0), (0, -1, 0), (0, 0, 1)),
    ((1, 0, 0), (0, 1, 0), (0, 0, -1)),
)


def faces_define():
    """CUBE_FACES: each face's right, up and forward as GLSL ``vec3`` constructors, in order."""
    return ", ".join(f"vec3({x}.0, {y}.0, {z}.0)" for face in FACES for x, y, z in face)


PART = ProgramPart(
    "cubes",
    samplers=(("FLOAT_2D", COLOR_SAMPLER), ("FLOAT_2D", DEPTH_SAMPLER)),
    defines=(("CUBES", True), ("CUBE_STEPS", STEPS), ("CUBE_FACES", faces_define())),
)
SETTLE_PART = ProgramPart("cubes_settle", defines=(("SSR_SETTLE", True),))

# A face's colour and view depth (the capture's normal target's w) into its slot of the atlas.
CUBE_COPY = Program(
    name="cube_copy",
    vertex="fullscreen.vert.glsl",
    fragment="cube_copy.frag.glsl",
    vertex_in=(("VEC2", "pos"),),
    push_constants=(("IVEC2", "origin"),),
    samplers=(("FLOAT_2D", "src_color"), ("FLOAT_2D", "src_normal")),
    outputs=(("VEC4", "out_color"), ("FLOAT", "out_depth")),
)


def face_size(width, height):
    """A cube face's side in texels: the power of two at or above two thirds of the frame's
    larger side, from 64 to 512 (a face spans 90 deg, a frame's side about 40 to 60: a face
    of two thirds of it is about the screen's own texel per degree). Measured on the mirror
    of ``hdri_spheres`` at 160x90: faces of 64 left 0.086 of Cycles, of 128 0.074."""
    side = max(int(width), int(height), 1) / 1.5
    return int(min(max(2 ** int(np.ceil(np.log2(max(side, 1.0)))), 64), 512))


def face_camera(position, k, near, far):
    """The ``Camera`` of face ``k`` (``FACES``) of a cube at ``position``: 90 deg square."""
    right, up, forward = (np.asarray(v, np.float64) for v in FACES[k])
    view = np.eye(4)
    view[0, :3], view[1, :3], view[2, :3] = right, up, -forward
    view[:3, 3] = -view[:3, :3] @ np.asarray(position, np.float64)
    n, f = float(near), float(far)
    projection = np.array(
        [[1.0, 0, 0, 0], [0, 1.0, 0, 0], [0, 0, -(f + n) / (f - n), -2.0 * f * n / (f - n)], [0, 0, -1.0, 0]]
    )
    return Camera(view, projection, False)


def influence_matrix(probe, origin):
    """The map from positions relative to ``origin`` into a Sphere probe's influence (its
    local axes over Influence Distance: inside where the length, or for a box the largest
    component, is under 1); None where degenerate."""
    m = np.asarray(probe.matrix, np.float64).copy()
    m[:3, :3] *= max(probe.influence_distance, 1e-9)
    m[:3, 3] -= np.asarray(origin, np.float64)
    return lightspace.finite_inverse(m)


def sees_influence(probe, camera):
    """Whether the camera may see some of ``probe``'s influence (its bounding sphere meets the
    view frustum's planes)."""
    r = probe.radius
    if not r > 0.0:
        return False
    vp = np.asarray(camera.projection, np.float64) @ np.asarray(camera.view, np.float64)
    centre = np.append(probe.position, 1.0)
    for row in (vp[3] + vp[0], vp[3] - vp[0], vp[3] + vp[1], vp[3] - vp[1], vp[3] + vp[2], vp[3] - vp[2]):
        n = np.linalg.norm(row[:3])
        if n > 0.0 and float(row @ centre) / n < -r:
            return False
    return True


class CubeReflections(Feature):
    name = "cubes"

    def __init__(self, renderer):
        super().__init__(renderer)
        self.face = None  # a face's capture (a Film: colour, normal and view depth)
        self.lit_pass = None
        self.color = self.depth = self._framebuffer = None  # the atlas
        self.probe = None  # this frame's Sphere probe
        self._camera = False  # this frame captures the camera's cube
        self._rows = None
        self._size = 0
        self._distance = 0.0
        self._captured = False
        self._batch = None

    @staticmethod
    def _choices(frame):
        """(the Sphere probe the frame uses or None, the others the camera sees, the camera's
        cube wanted)."""
        if not (frame.accumulate and frame.sample_count > 1) or not reflective_materials(frame.draws):
            return None, [], False
        camera = frame.camera
        seen = [p for p in getattr(frame.snapshot, "spheres", ()) if sees_influence(p, camera)]
        seen.sort(key=lambda p: float(np.linalg.norm(p.position - camera.position)) - p.radius)
        own = bool(getattr(frame.settings, "screen_space_reflections", True))
        return (seen[0] if seen else None), seen[1:], own

    def wanted(self, frame):
        probe, _others, own = self._choices(frame)
        return probe is not None or own

    def plan(self, frame):
        self.probe, others, self._camera = self._choices(frame)
        if frame.request.samples[0] == 0 or self._size != face_size(*frame.size):
            self._captured = False
        self._distance = longest_ray(frame.draws)
        for p in others:
            frame.stats.messages.append(f"Penumbra: Sphere Light Probe '{p.name}' is not drawn: a frame uses one")

    def _cubes(self, frame):
        """[(row in the atlas, centre, near, far)] of this frame's cubes: the probe's, the camera's."""
        out = []
        if self.probe is not None:
            out.append((len(out), self.probe.position, self.probe.clip_start, self.probe.clip_end))
        if self._camera:
            camera = frame.camera
            near, far = _clip_range(camera)
            out.append((len(out), np.asarray(camera.position, np.float64), near, far))
        return out

    def _ensure(self, size, count):
        import gpu

        pool = self.renderer.caches.pool
        if self.face is None:
            from ..lit_pass import LitPass

            caches = self.renderer.caches
            self.face = Film(caches.shaders, pool)
            self.lit_pass = LitPass(caches, self.face)
        self.face.ensure(size, size, True)
        shape = (3 * size, 2 * size * count)
        if self.color is None or (self.color.width, self.color.height) != shape:
            self._give()
            self.color = new_texture(pool, shape, "RGBA32F")
            self.depth = new_texture(pool, shape, "R32F")
            self._framebuffer = gpu.types.GPUFrameBuffer(color_slots=(self.color, self.depth))
        self._size = size

    def before_lit(self, frame, sample):
        if self._captured or sample.settle_test or sample.pilot:
            return
        cubes = self._cubes(frame)
        if not cubes:
            return
        import dataclasses

        size = face_size(*frame.size)
        with frame.clock.stage("cubes"):
            self._ensure(size, len(cubes))
            parts = captured_parts(frame, sample)
            for row, centre, near, far in cubes:
                for k in range(6):
                    camera = face_camera(centre, k, near, far)
                    capture = dataclasses.replace(
                        sample, view_camera=camera, cameras=(camera, camera, None), data=None, seen=None, masks=None
                    )
                    self.renderer.capture(frame, capture, self.lit_pass, parts)
                    self._copy(k, row, size)
                    frame.stats.cube_faces += 1
        self._captured = True
        self._rows = self._frame_rows(frame, cubes, size)

    def _copy(self, k, row, size):
        import gpu
        from gpu_extras.batch import batch_for_shader

        shader = self.renderer.shaders.get(CUBE_COPY)
        if self._batch is None:
            self._batch = batch_for_shader(shader, "TRIS", {"pos": ((-1, -1), (3, -1), (-1, 3))})
        batch = self._batch
        x0, y0 = (k % 3) * size, (k // 3 + 2 * row) * size
        with self._framebuffer.bind():
            gpu.state.viewport_set(x0, y0, size, size)
            gpu.state.depth_test_set("NONE")
            gpu.state.blend_set("NONE")
            shader.bind()
            shader.uniform_int("origin", (x0, y0))
            shader.uniform_sampler("src_color", self.face.color)
            shader.uniform_sampler("src_normal", self.face.normal)
            batch.draw(shader)

    def _frame_rows(self, frame, cubes, size):
        origin = np.asarray(frame.origin, np.float64)
        rows = {
            "cube_params": (float(size), self._distance, THICKNESS, 0.0),
            "cube_probe": (0.0, 0.0, 0.0, -1.0),
            "cube_probe_influence": np.zeros((4, 4)),
            "cube_probe_shape": (0.0, 0.0, 0.0, 0.0),
            "cube_camera": (0.0, 0.0, 0.0, -1.0),
        }
        for row, centre, _near, _far in cubes:
            if self.probe is not None and row == 0:
                influence = influence_matrix(self.probe, origin)
                if influence is None:
                    continue
                rows["cube_probe"] = (*map(float, centre - origin), float(row))
                rows["cube_probe_influence"] = influence
                rows["cube_probe_shape"] = (float(self.probe.box), float(self.probe.falloff), 0.0, 0.0)
            else:
                rows["cube_camera"] = (*map(float, centre - origin), float(row))
        return rows

    def lit(self, frame, sample):
        if sample.settle_test:
            return LitPart(program=SETTLE_PART)
        if not self._captured or self._rows is None:
            return LitPart()
        return LitPart(
            program=PART,
            rows=self._rows,
            samplers={COLOR_SAMPLER: self.color, DEPTH_SAMPLER: self.depth},
        )

    def memory_bytes(self, frame):
        if not frame.stats.cube_faces or self.color is None:
            return 0
        return 20 * self.color.width * self.color.height + self.face.target_bytes(True, False)

    def _give(self):
        pool = self.renderer.caches.pool
        if pool is not None and self.color is not None:
            pool.give([self.color, self.depth])
        self.color = self.depth = self._framebuffer = None

    def release(self):
        if self.face is not None:
            self.face.release()
        self._give()
        self.face = self.lit_pass = None
        self._rows = None
        self._captured = False


def _clip_range(camera):
    """The camera's (near, far) clip distances from its projection (a perspective one's)."""
    p = np.asarray(camera.projection, np.float64)
    a, b = p[2, 2], p[2, 3]
    if camera.is_ortho or not (abs(a + 1.0) > 1e-12 and abs(a - 1.0) > 1e-12):
        return 0.01, 1000.0
    near, far = b / (a - 1.0), b / (a + 1.0)
    if not (np.isfinite(near) and np.isfinite(far) and far > near > 0.0):
        return 0.01, 1000.0
    return float(near), float(far)
