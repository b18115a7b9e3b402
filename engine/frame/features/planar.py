"""Planar reflections from Blender's Plane Light Probes (lib/planar.glsl), as EEVEE honours
them: each sample draws the scene mirrored about the probe's plane with the lit pass (the same
lights, maps and world as the sample, through the sample's camera reflected in the plane, what
lies under the plane clipped away), and a glossy lobe of a surface in the probe's influence
traces its ray, drawn anew each sample, through that capture and its view depth instead of
the screen. For a flat mirror, floor or water the reflection is the mirrored camera's image,
exact: what stands behind the camera, off the screen or behind another object shows too, and
a rough lobe's rays spread over it. Rays the capture does not meet fall back to the scene's
reflections on the screen (``reflections.py``) and then the world.

The influence is EEVEE's: the probe object's local square (-1..1 in X and Y, its scale) out to
Influence Distance on either side of the plane, for surfaces that face the plane's side of its
normal; what lies under the plane or less than Clipping Offset above it (the mirror's own
surface) is left out of the capture. Unlike the screen's reflections
a capture needs no earlier sample: the first sample and a one-sample frame (the viewport while
the view moves) show the mirror too.

What stays approximate, said once in the report: a frame draws one probe's capture (the one
whose mirror covers most of the image; the others are named); the capture takes the sample's
lights as the camera's view culled them and their maps as fitted to it, and the world's ratio
of the sample's own directions (``Feature.capture``); surfaces in the capture reflect the
world, not the scene. Wanted where a Plane probe's mirror is in
view and a surface may have a traced lobe (``reflective_materials``); a scene without either
pays nothing."""

import dataclasses

import numpy as np

from ....shaders.loader import ProgramPart
from ...shadows import lightspace
from ..draw_list import longest_ray, reflective_materials
from ..film import Film
from .base import Feature, LitPart, captured_parts

COLOR_SAMPLER = "planar_color"
DEPTH_SAMPLER = "planar_depth"  # the capture's normal target: its view depth in w
THICKNESS = 0.02  # a surface's thickness, as a fraction of its depth, that a ray behind it still meets

PART = ProgramPart(
    "planar",
    samplers=(("FLOAT_2D", COLOR_SAMPLER), ("FLOAT_2D", DEPTH_SAMPLER)),
    defines=(("PLANAR", True),),
)
# The capture's own lit pass: what lies under the mirror is clipped (lit.frag.glsl CLIP_PLANE).
CAPTURE_PART = ProgramPart("planar_capture", defines=(("CLIP_PLANE", True),))
# The settle test's: a pixel a capture reflects into is never settled (each sample's differs).
SETTLE_PART = ProgramPart("planar_settle", defines=(("SSR_SETTLE", True),))

APPROXIMATE = (
    "Penumbra: a Plane Light Probe's reflection takes the lights as the camera's view culls them, "
    "their shadow maps as fitted to it"
)


def reflection_matrix(normal, point):
    """The 4x4 reflection about the plane through ``point`` with unit ``normal``."""
    n = np.asarray(normal, np.float64).reshape(3)
    m = np.eye(4)
    m[:3, :3] -= 2.0 * np.outer(n, n)
    m[:3, 3] = 2.0 * float(n @ np.asarray(point, np.float64)) * n
    return m


def mirrored_camera(camera, probe):
    """``camera`` (``extract.Camera``) reflected in ``probe``'s plane: it sees, at each pixel of
    the plane, what the plane mirrors there (its view is the camera's times the reflection, so
    it turns the winding of what it draws)."""
    mirror = reflection_matrix(probe.normal, probe.point)
    return dataclasses.replace(camera, view=np.asarray(camera.view, np.float64) @ mirror)


def plane_row(probe, origin, offset=0.0):
    """(normal, -normal . point) of ``probe``'s plane for positions relative to ``origin``,
    raised ``offset`` along its normal; dot((P, 1), row) < 0 under it."""
    n = probe.normal
    d = -float(n @ (probe.point - np.asarray(origin, np.float64))) - float(offset)
    return (*map(float, n), d)


def influence_matrix(probe, origin):
    """The map from positions relative to ``origin`` into the probe's influence box (EEVEE's:
    the object's local X and Y, its normal scaled to Influence Distance; -1..1 inside)."""
    m = np.asarray(probe.matrix, np.float64).copy()
    m[:3, 2] = probe.normal * max(probe.influence_distance, 1e-9)
    m[:3, 3] -= np.asarray(origin, np.float64)
    return lightspace.finite_inverse(m)


def coverage(probe, camera, size):
    """The share of the image the probe's mirror covers (its square's projected area over the
    image's, clipped to it; 0 out of view or where the camera sees the mirror's back)."""
    n = probe.normal
    if n is None:
        return 0.0
    corners = probe.corners
    if camera.is_ortho:
        if float(camera.forward @ n) >= 0.0:
            return 0.0
    elif float(n @ (camera.position - probe.point)) <= 0.0:
        return 0.0
    h = np.c_[corners, np.ones(4)] @ (np.asarray(camera.projection) @ np.asarray(camera.view)).T
    if np.any(h[:, 3] <= 1e-9):
        return 1.0  # the mirror reaches behind the camera: count it as filling the view
    xy = np.clip(h[:, :2] / h[:, 3:4], -1.0, 1.0)
    x, y = xy[:, 0], xy[:, 1]
    area = 0.5 * abs(float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))
    return min(area / 4.0, 1.0)


class PlanarReflections(Feature):
    name = "planar"

    def __init__(self, renderer):
        super().__init__(renderer)
        self.targets = None  # the capture's targets (a Film of its own: colour, normal and view depth)
        self.lit_pass = None
        self.probe = None  # this frame's probe
        self._distance = 0.0
        self._rows = None

    @staticmethod
    def _chosen(frame):
        planes = [p for p in getattr(frame.snapshot, "planes", ()) if p.normal is not None]
        if not planes or not reflective_materials(frame.draws):
            return None, []
        scored = sorted(((coverage(p, frame.camera, frame.size), i) for i, p in enumerate(planes)), reverse=True)
        seen = [planes[i] for c, i in scored if c > 0.0]
        return (seen[0] if seen else None), seen[1:]

    def wanted(self, frame):
        return self._chosen(frame)[0] is not None

    def plan(self, frame):
        self.probe, others = self._chosen(frame)
        self._distance = longest_ray(frame.draws)
        messages = frame.stats.messages
        messages.append(APPROXIMATE)
        for p in others:
            messages.append(f"Penumbra: Plane Light Probe '{p.name}' is not drawn: a frame reflects one Plane probe")

    def _ensure(self, size):
        if self.targets is None:
            from ..lit_pass import LitPass

            caches = self.renderer.caches
            self.targets = Film(caches.shaders, caches.pool)
            self.lit_pass = LitPass(caches, self.targets)
        self.targets.ensure(size[0], size[1], True)

    def before_lit(self, frame, sample):
        if sample.settle_test:
            self._rows = None
            return
        probe = self.probe
        with frame.clock.stage("planar"):
            self._ensure(frame.size)
            view_camera = mirrored_camera(sample.view_camera, probe)
            draws = [d for d in sample.draws if d.instance.camera]
            corners = np.stack([d.corners for d in draws]) if draws else np.zeros((0, 8, 3))
            depths = lightspace.box_depth_range(view_camera.projection, view_camera.view, corners, view_camera.is_ortho)
            fitted = lightspace.depth_fitted(view_camera.projection, view_camera.is_ortho, depths)
            raster = dataclasses.replace(view_camera, projection=fitted)
            offset = max(probe.clip_start, 1e-6 * max(1.0, float(np.max(np.abs(probe.point - frame.origin)))))
            capture = dataclasses.replace(
                sample,
                view_camera=view_camera,
                cameras=(raster, view_camera, None),
                mirrored=True,
                data=None,
                seen=None,
                masks=None,
            )
            part = LitPart(program=CAPTURE_PART, rows={"clip_plane": plane_row(probe, frame.origin, offset)})
            self.renderer.capture(frame, capture, self.lit_pass, (part, *captured_parts(frame, sample)))
            view = np.asarray(view_camera.view, np.float64) @ lightspace.from_origin(frame.origin)
            self._rows = {
                "planar_view": view,
                "planar_view_proj": np.asarray(view_camera.projection, np.float64) @ view,
                "planar_influence": influence_matrix(probe, frame.origin),
                "planar_plane": plane_row(probe, frame.origin),
                "planar_params": (self._distance, THICKNESS, 0.0, 0.0),
            }
            frame.stats.planar_captures += 1

    def lit(self, frame, sample):
        if sample.settle_test:
            return LitPart(program=SETTLE_PART)
        if self._rows is None or self._rows["planar_influence"] is None:
            return LitPart()
        return LitPart(
            program=PART,
            rows=self._rows,
            samplers={COLOR_SAMPLER: self.targets.color, DEPTH_SAMPLER: self.targets.normal},
        )

    def resolve(self, frame):
        self._rows = None

    def memory_bytes(self, frame):
        if not frame.stats.planar_captures or self.targets is None:
            return 0
        return self.targets.target_bytes(True, False)

    def release(self):
        if self.targets is not None:
            self.targets.release()
        self.targets = self.lit_pass = None
        self._rows = None
