"""Depth of field (Camera > Depth of Field; ``lens.py``): each sample of a frame of several
looks from its own point of the lens, so the frame's average blurs what is out of focus. Its
maps and light bins are planned for what those samples see (the widest circle of confusion's
reach beyond the image), and settling tests as far as that circle reaches.

A one-sample frame looks through the lens's centre, and says so. Off (not registered), every
sample looks through the lens's centre."""

from ...shadows import lightspace
from ..draw_list import corners_of
from ..lens import lens_camera, lens_offset, lens_reach
from .base import Feature, across_samples


class DepthOfField(Feature):
    name = "depth_of_field"

    def wanted(self, frame):
        return frame.camera.lens is not None and across_samples(frame, "depth of field", "through the lens's centre")

    def plan(self, frame):
        """The lens's reach: its widest circle of confusion's radius over the depths of what is drawn."""
        camera = frame.camera
        lens = 0.0
        if frame.draws:
            depths = lightspace.box_depth_range(
                camera.projection, camera.view, corners_of(frame.draws), camera.is_ortho
            )
            lens = lens_reach(camera, depths, *frame.size) if depths is not None else 0.0
        frame.stats.lens_reach = lens
        frame.lens_reach = lens
        frame.reach += lens

    def prepare(self, frame, sample):
        # The pilot (settling) looks through the lens's centre, as the frame's plan does.
        if not sample.pilot and sample.camera.lens:
            sample.view_camera = lens_camera(sample.camera, lens_offset(sample.index, sample.camera.lens))
