"""Motion blur (Render Properties > Motion Blur; ``motion.py``): each sample of a frame of
several is drawn at its own time in the shutter, its objects, lights and camera where they are
then, and plans its maps from its own scene.

A one-sample frame is drawn at the frame's time, and says so. Off (not registered), every
sample is drawn at the frame's time."""

import dataclasses

from .. import motion as motion_mod
from ..draw_list import draw_list
from .base import Feature, across_samples


class MotionBlur(Feature):
    name = "motion_blur"

    def wanted(self, frame):
        motion = frame.request.motion
        return motion is not None and motion.moves and across_samples(frame, "motion blur", "at the frame's time")

    def plan(self, frame):
        frame.motion = frame.request.motion

    def prepare(self, frame, sample):
        """The sample's time in the shutter moves objects, lights and camera."""
        if sample.pilot:
            return
        motion = frame.motion
        u = motion_mod.sample_time(sample.index, frame.sample_count, motion.curve)
        instances = motion_mod.instances_at(frame.snapshot.instances, motion, u)
        snapshot = dataclasses.replace(frame.snapshot, instances=instances)
        if motion.shapes:
            snapshot = self._deformed(frame, snapshot, motion, u)
        renderer = self.renderer
        sample.draws = draw_list(
            snapshot, renderer.caches.batches, frame.stats, frame.origin, sample.camera, frame.settings, frame.size
        )
        sample.lights = motion_mod.lights_at(sample.lights, motion, u)
        sample.camera = sample.view_camera = motion_mod.camera_at(sample.camera, motion, u)
        renderer.shadow_pass.begin_frame(
            frame.reach, frame.reflective, frame.receivers
        )  # this sample's maps from its own scene

    @staticmethod
    def _deformed(frame, snapshot, motion, u):
        """``snapshot`` with its deforming meshes' vertices where they are at shutter fraction
        ``u`` (each drawn from geometry of its own, kept for this frame only); a mesh whose
        vertices the steps cannot give keeps the frame's shape and is named."""
        geometry = dict(snapshot.geometry)
        instances = []
        made = {}
        for inst in snapshot.instances:
            shapes = motion.shapes.get(inst.motion_key)
            if shapes is None or inst.key not in snapshot.geometry:
                instances.append(inst)
                continue
            if inst.key not in made:
                made[inst.key] = motion_mod.deformed(snapshot.geometry[inst.key], shapes, motion.times, u)
            geo = made[inst.key]
            if geo is None:
                message = (
                    "Penumbra: a deforming mesh's vertices could not be followed through the shutter: "
                    "drawn at the frame's shape"
                )
                if message not in frame.stats.messages:
                    frame.stats.messages.append(message)
                instances.append(inst)
                continue
            key = (*inst.key, "deformed")
            geometry[key] = geo
            instances.append(dataclasses.replace(inst, key=key))
        return dataclasses.replace(snapshot, geometry=geometry, instances=instances)
