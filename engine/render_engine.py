"""The RenderEngine subclass: thin glue from Blender's callbacks to the Renderer."""

import dataclasses
import math
import sys
import traceback

import bpy
import numpy as np

from . import gpu_pool, store
from .frame import cryptomatte, sampling
from .frame.output import (
    CRYPTOMATTE_SWITCHES,
    DENOISING_PASSES,
    FURTHER_PASSES,
    LIGHT_COLOR,
    cryptomatte_levels,
    divided,
    drawn_passes,
    frame_in_region,
    mist_pass,
    pass_name,
    render_views,
    render_window,
    requested_passes,
    unsupported_in_use,
    view_distance_scale,
    viewport_window,
)
from .frame.sampling import adaptive_settings
from .scene.extract import SceneCache, camera_from_scene, camera_from_view, camera_lens, matrix_np, motion_matrices

ENDLESS_SAMPLES = 64  # how finely soft lights are split when the viewport refines without end

# The Emission pass's name on this Blender line, as its own engines register it (the
# compositor's Render Layers socket): "Emit" up to 4.5, "Emission" from 5.0.
EMISSION_PASS = "Emission" if bpy.app.version >= (5, 0, 0) else "Emit"

# What the render report and the viewport's text say when a frame stopped before its last sample.
STOPPED = {"converged": "Noise Threshold reached", "time limit": "Time Limit reached"}


class PenumbraEngineCore:
    """What the viewport and final renders share. Kept apart from the registered class so
    other RenderEngine classes (the test harness) can reuse it without subclassing a
    registered type."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.cache = SceneCache()
        self.renderer = None
        self.texture_pool = None  # gpu_pool.TexturePool of final renders (set by render())
        self.last_stats = None
        self._reported = None
        self._shown = None  # (view key, FrameOutput) of the frame the viewport shows
        self._started = 0.0  # when the viewport's refinement of the shown frame began (monotonic)
        self._stopped = ""  # why it stopped before its last sample (FrameStats.stopped)

    def free_gpu(self):
        """Release this instance's GPU resources. Call it while the GPU context is active:
        freeing GPU objects later, from a destructor without a context, aborts Blender 4.5."""
        if self.renderer is not None:
            self.renderer.release()  # its textures go to the pool, if it has one
        self.renderer = None
        self._shown = None
        self.cache.clear()

    def render_frame(
        self,
        depsgraph,
        camera,
        width,
        height,
        pixel_scale=1.0,
        aux=True,
        samples=(0, 1),
        sample_count=1,
        on_sample=None,
        emission=False,
        adaptive=None,
        deadline=None,
        navigating=False,
        motion=None,
        passes=(),
        cryptomatte=(6, (0, 1, 2)),
    ):
        """Extract, then render samples ``samples`` of a frame of ``sample_count`` samples
        (``Renderer.render``); returns the renderer's FrameOutput. ``pixel_scale`` scales the
        post layers' sizes in pixels (a final render's resolution %); ``aux``: also produce the
        depth, shadow and normal targets (passes), not only colour. ``navigating``: a frame
        while the view moves (``Renderer.render``: its maps keep the last such frame's sizes)."""
        from .frame.renderer import FrameRequest, Renderer

        if self.renderer is None:
            final = self.texture_pool is not None
            shaders = gpu_pool.final_shaders() if final else None
            self.renderer = Renderer(self.texture_pool, shaders, store=self.cache.store if final else None)
        scene = depsgraph.scene
        self.cache.uv_pass = "UV" in passes  # every mesh's UV map read (geometry keyed by what it reads)
        snapshot = self.cache.snapshot(depsgraph)
        settings = scene.penumbra.render_settings(
            frame=scene.frame_current,
            # View Layer > Filter > Environment off: the world lights, the camera does not see it.
            film_transparent=scene.render.film_transparent or not getattr(depsgraph.view_layer, "use_sky", True),
            pixel_scale=pixel_scale,
            use_simplify=scene.render.use_simplify,
        )
        request = FrameRequest(
            camera,
            settings,
            width,
            height,
            aux=aux,
            samples=samples,
            sample_count=sample_count,
            emission=emission,
            adaptive=adaptive,
            deadline=deadline,
            navigating=navigating,
            motion=motion,
            passes=tuple(passes),
            cryptomatte=cryptomatte,
        )
        out = self.renderer.render(snapshot, request, on_sample=on_sample)
        self.last_stats = out.stats
        return out

    def viewport_frame(self, depsgraph, view_matrix, window_matrix, width, height, lens=None):
        """The frame a viewport redraw shows, one sample at a time:
        * the view moved since the last frame: one sample at ``navigation_scale`` of the
          region's resolution (post sizes scaled alike);
        * otherwise, after any change (``view_update`` calls ``scene_changed``) or a stop: the
          first full-resolution sample, then one more sample per redraw, accumulated, until
          ``viewport_samples`` (0: without end), or until adaptive sampling finds every pixel
          converged or the viewport's time limit passes; then the same frame again, nothing
          rendered.
        Sample k of the viewport is sample k of a final render, so N redraws show what a final
        render of N samples shows. Returns (FrameOutput, whether it rendered); ``refining()``
        says whether another redraw would render more."""
        key = (width, height, tuple(map(tuple, view_matrix)), tuple(map(tuple, window_matrix)), lens)
        settings = depsgraph.scene.penumbra
        target = int(settings.viewport_samples)
        count = target if target > 0 else ENDLESS_SAMPLES
        adaptive = adaptive_settings(
            settings.use_preview_adaptive_sampling,
            settings.preview_adaptive_threshold,
            settings.preview_adaptive_min_samples,
            settings.preview_time_limit,
            target,
        )
        shown = self._shown
        if shown is not None and shown[0] == key and shown[1].width == width:
            done = shown[2]
            if not self._wants_sample(done, target) or self._stopped:
                return shown[1], False
            camera = dataclasses.replace(camera_from_view(view_matrix, window_matrix), lens=lens)
            out = self._viewport_sample(depsgraph, camera, width, height, done, count, adaptive)
            self._shown = (key, out, done + out.stats.samples, target)
            return out, True
        scale = float(settings.navigation_scale)
        moving = shown is not None and shown[0][:2] == (width, height) and shown[0] != key and scale < 1.0
        camera = dataclasses.replace(camera_from_view(view_matrix, window_matrix), lens=lens)
        self._shown = None
        self._stopped = ""
        if moving:
            w, h = max(1, round(width * scale)), max(1, round(height * scale))
            out = self.render_frame(depsgraph, camera, w, h, pixel_scale=w / width, aux=False, navigating=True)
            self._shown = (key, out, 0, target)
        else:
            self._started = sampling.clock()
            out = self._viewport_sample(depsgraph, camera, width, height, 0, count, adaptive)
            self._shown = (key, out, 1, target)
        return out, True

    def _viewport_sample(self, depsgraph, camera, width, height, done, count, adaptive):
        """Sample ``done`` of the viewport's frame of ``count``, within the time limit counted
        from its first sample (``_started``); remembers why refinement stopped, if it did."""
        deadline = self._started + adaptive.time_limit if adaptive is not None and adaptive.time_limit else None
        out = self.render_frame(
            depsgraph,
            camera,
            width,
            height,
            aux=False,
            samples=(done, done + 1),
            sample_count=count,
            adaptive=adaptive,
            deadline=deadline,
        )
        self._stopped = out.stats.stopped
        return out

    @staticmethod
    def _wants_sample(done, target):
        return target == 0 or done < target

    def refining(self):
        """Whether the next redraw would render more (a navigation preview to refine, or
        samples still to accumulate)."""
        shown = self._shown
        if shown is None:
            return False
        key, out, done, target = shown
        return out.width < key[0] or (self._wants_sample(done, target) and not self._stopped)

    def viewport_status(self):
        """'Sample k/N' of the frame the viewport shows ('' before the first), and why it
        stopped early if it did ('Sample 40/64 | Noise Threshold reached')."""
        if self._shown is None or self._shown[2] == 0:
            return ""
        done, target = self._shown[2], self._shown[3]
        text = f"Sample {done}/{target}" if target else f"Sample {done}"
        return f"{text} | {STOPPED[self._stopped]}" if self._stopped else text

    def scene_changed(self):
        """Something in the scene changed: the next viewport redraw renders afresh."""
        self._shown = None
        self._stopped = ""

    def draw_display(self, scene, texture, width, height, window=None):
        """Draw a scene-linear texture through Blender's colour management (view transform,
        look, exposure, gamma): the viewport shows what the final render saves. ``window``
        (an ``output.Window``): only those pixels show (a render region)."""
        import gpu
        from gpu_extras.presets import draw_texture_2d

        gpu.state.blend_set("ALPHA_PREMULT")
        if window is not None:
            gpu.state.scissor_set(window.x0, window.y0, window.width, window.height)
            gpu.state.scissor_test_set(True)
        self.bind_display_space_shader(scene)
        draw_texture_2d(texture, (0, 0), width, height)
        self.unbind_display_space_shader()
        if window is not None:
            gpu.state.scissor_test_set(False)
        gpu.state.blend_set("NONE")

    def viewport_region(self, context, depsgraph, width, height):
        """The part of the viewport a render region leaves visible (``output.viewport_window``):
        the scene's Render Region in camera view, the viewport's own elsewhere."""
        rv3d, space, scene = context.region_data, context.space_data, depsgraph.scene
        if rv3d.view_perspective == "CAMERA" and scene.camera is not None:
            r = scene.render
            cam = scene.camera.evaluated_get(depsgraph)
            corners = [cam.matrix_world @ v for v in cam.data.view_frame(scene=scene)]
            frame = frame_in_region(corners, rv3d.perspective_matrix, width, height)
            border = (r.border_min_x, r.border_min_y, r.border_max_x, r.border_max_y)
            return viewport_window(width, height, r.use_border and frame is not None, border, frame)
        border = (
            space.render_border_min_x,
            space.render_border_min_y,
            space.render_border_max_x,
            space.render_border_max_y,
        )
        return viewport_window(width, height, space.use_render_border, border)

    def read_vectors(self, depsgraph, width, height):
        """The scene at the previous and next frames (``vectors.Neighbours``): what the Vector
        pass measures the motion against, as Cycles does (``frame_set`` to each, then back)."""
        from .frame.vectors import Neighbours

        scene = depsgraph.scene
        frame, subframe = scene.frame_current, float(scene.frame_subframe)
        read = []
        try:
            for step in (-1, 1):
                self.frame_set(frame + step, subframe)
                cam = camera_from_scene(depsgraph, scene, width, height)
                read.append((motion_matrices(depsgraph), cam.projection @ cam.view))
        finally:
            self.frame_set(frame, subframe)
        return Neighbours(read[0][0], read[1][0], read[0][1], read[1][1])

    @staticmethod
    def _vector_pass(out, camera, neighbours, width, height):
        """The Vector pass of frame ``out`` (``vectors.vector_pass``), full frame."""
        from .frame.vectors import vector_pass

        position = out.pass_array("POSITION", 3)
        numbers = out.pass_array("DRAW", 1)[..., 0]
        view_proj = camera.projection @ camera.view
        return vector_pass(position, numbers, out.passes["DRAWS"], view_proj, neighbours, width, height)

    def read_motion(self, depsgraph):
        """What moves during this frame's shutter (Render > Motion Blur: its Position, Shutter
        and Shutter Curve), read at the shutter's steps (``motion_steps``; ``frame_set`` to
        each, then the frame set back): (``motion.Motion``, or None where nothing moves or
        motion blur is off; report messages). An object with Cycles' Object > Motion Blur off
        does not blur; deforming meshes move with their object, at the frame's shape."""
        from .frame.motion import CURVE_POINTS, Motion, moving_only

        scene = depsgraph.scene
        r = scene.render
        shutter = float(r.motion_blur_shutter)
        if not r.use_motion_blur or not (math.isfinite(shutter) and shutter > 0.0):
            return None, []
        if not getattr(depsgraph.view_layer, "use_motion_blur", True):  # View Layer > Filter > Motion Blur
            return None, []
        start = {"START": 0.0, "CENTER": -0.5, "END": -1.0}.get(r.motion_blur_position, -0.5) * shutter
        frame, subframe = scene.frame_current, float(scene.frame_subframe)
        count = motion_steps(scene.objects)
        times = tuple(k / (count - 1) for k in range(count))
        deforming = {
            ob.name_full
            for ob in scene.objects
            if ob.type == "MESH" and ob.visible_get() and _blurs(ob, deform=True) and _deforms(ob, scene)
        }
        steps, cameras, shapes = [], [], []
        try:
            for t in times:
                at = frame + subframe + start + t * shutter
                whole = math.floor(at)
                self.frame_set(int(whole), at - whole)
                steps.append(motion_matrices(depsgraph))
                cameras.append(_camera_view(scene.camera.evaluated_get(depsgraph)))
                shapes.append(motion_shapes(depsgraph, deforming) if deforming else {})
        finally:
            self.frame_set(frame, subframe)
        reference = _camera_view(scene.camera.evaluated_get(depsgraph))
        still = {ob.name_full for ob in scene.objects if not _blurs(ob)}
        common = {k for k in set(steps[0]).intersection(*steps[1:]) if k[0] not in still}
        moving = moving_only({k: [m[k] for m in steps] for k in common})
        moves = any(not np.array_equal(cameras[0], c) for c in cameras[1:]) and _blurs(scene.camera)
        curve = _shutter_curve(r.motion_blur_shutter_curve, CURVE_POINTS)
        camera = cameras if moves else None
        deformed, changing = deforming_shapes(shapes)
        motion = Motion(
            times=times,
            instances=moving,
            lights=moving,
            camera=camera,
            camera_ref=reference,
            curve=curve,
            shapes=deformed,
        )
        messages = []
        if changing:
            names = ", ".join(f"'{n}'" for n in changing[:3]) + (" ..." if len(changing) > 3 else "")
            messages.append(
                f"Penumbra: {names} change their topology during the shutter: drawn at the frame's shape, "
                "moving with their object"
            )
        return (motion if motion.moves else None), messages


# Cycles' most steps of an object's motion (Object::MAX_MOTION_STEPS).
MAX_MOTION_STEPS = 129


def motion_steps(objects):
    """How many times in the shutter transforms are read: Cycles' Object > Motion Blur >
    Steps n gives 2^n + 1 (3 at its default 1), the most of any object that blurs, at most
    MAX_MOTION_STEPS (so objects with fewer steps still have theirs among them)."""
    most = 1
    for ob in objects:
        settings = getattr(ob, "cycles", None)
        if settings is not None and _blurs(ob):
            most = max(most, int(getattr(settings, "motion_steps", 1)))
    return min((2 << (min(most, 64) - 1)) + 1, MAX_MOTION_STEPS)


def _blurs(ob, deform=False):
    """Cycles' Object > Motion Blur (and its Deformation, ``deform``): on unless switched off."""
    settings = getattr(ob, "cycles", None)
    if settings is None:
        return True
    return bool(getattr(settings, "use_motion_blur", True)) and (
        not deform or bool(getattr(settings, "use_deform_motion", True))
    )


class PenumbraRenderEngine(PenumbraEngineCore, bpy.types.RenderEngine):
    bl_idname = "PENUMBRA"
    bl_label = "Penumbra"
    bl_use_preview = False
    bl_use_gpu_context = True
    bl_use_eevee_viewport = True  # Material Preview shading falls back to EEVEE, as for Cycles
    bl_use_shading_nodes_custom = False

    # --- final render ---------------------------------------------------------------------

    def break_requested(self):
        """Whether the user asked the render to stop (Esc, F12's cancel): Blender's
        ``test_break``, asked before each view and after each sample. (RNA's own method
        shadows any Python attribute of that name, so the tests stand in for Esc here.)"""
        return self.test_break()

    def update_render_passes(self, scene=None, renderlayer=None):
        self.register_pass(scene, renderlayer, "Combined", 4, "RGBA", "COLOR")
        if renderlayer.use_pass_z:
            self.register_pass(scene, renderlayer, "Depth", 1, "Z", "VALUE")
        if renderlayer.penumbra.use_pass_shadow:
            self.register_pass(scene, renderlayer, "Shadow", 1, "X", "VALUE")
        if renderlayer.use_pass_normal:
            self.register_pass(scene, renderlayer, "Normal", 3, "XYZ", "VECTOR")
        if renderlayer.use_pass_mist:
            self.register_pass(scene, renderlayer, "Mist", 1, "Z", "VALUE")
        if renderlayer.penumbra.use_pass_lit:
            self.register_pass(scene, renderlayer, "Lit", 4, "RGBA", "COLOR")
        if renderlayer.use_pass_emit:
            self.register_pass(scene, renderlayer, EMISSION_PASS, 3, "RGB", "COLOR")
        for name, channels, chan_id, kind in further_passes(renderlayer):
            self.register_pass(scene, renderlayer, name, channels, chan_id, kind)

    def render(self, depsgraph):
        """Render the pixels Blender asks for: the render region of the frame at Blender's
        integer resolution, into this view layer's own result, once per view of a multiview
        render. Each result is written whole or cancelled, never left half-written; a render
        cancelled (Esc) after a sample writes the samples it has."""
        scene = depsgraph.scene
        layer = depsgraph.view_layer.name
        self.texture_pool = gpu_pool.FINAL_RENDERS
        self.cache.store = store.STORE  # meshes and their batches kept between final renders
        store.STORE.collect()  # what a file load emptied out of it, freed in this GPU context
        store.STORE.pressure()  # the system short of memory: the store sheds its older half
        r = scene.render
        self.texture_pool.begin_render(
            (scene.name, scene.frame_current, self.resolution_x, self.resolution_y, r.use_border)
        )
        if scene.camera is None:
            self.report({"ERROR"}, f"Penumbra: scene '{scene.name}' has no active camera; set one in Scene Properties")
            return
        width, height = self.resolution_x, self.resolution_y
        window = render_window(
            width, height, r.use_border, (r.border_min_x, r.border_min_y, r.border_max_x, r.border_max_y)
        )
        if window.width <= 0 or window.height <= 0:
            self.report({"ERROR"}, "Penumbra: the render region is empty; widen it in the Output properties")
            return
        views = render_views(r)
        vl = depsgraph.view_layer
        aux = vl.use_pass_z or vl.use_pass_mist or vl.use_pass_normal or vl.penumbra.use_pass_shadow or vl.use_pass_emit
        reported = set()
        for message in unsupported_in_use(scene.camera.data, r, depsgraph.view_layer):
            self.report({"WARNING"}, message)
        try:
            motion, messages = self.read_motion(depsgraph)
            neighbours = self.read_vectors(depsgraph, width, height) if depsgraph.view_layer.use_pass_vector else None
        except Exception as exc:  # a render must end with a message, never a crash
            traceback.print_exc(file=sys.stderr)
            motion, messages = None, [f"Penumbra: motion blur could not be read ({exc}): rendered without it"]
        for message in messages:
            self.report({"WARNING"}, message)
        try:
            limit = _gpu_texture_limit()
            if max(width, height) > limit:
                self.report(
                    {"ERROR"},
                    f"Penumbra: {width}x{height} is larger than this GPU's largest texture ({limit} pixels a "
                    "side); lower the resolution or its %",
                )
                return
            for index, view in enumerate(views):
                if self.break_requested():
                    return
                self.update_stats("", f"Penumbra | {layer}{' | ' + view if view else ''} | rendering")
                camera = self._view_camera(depsgraph, view, width, height)
                options = scene.penumbra
                # View Layer > Override > Samples (0: the scene's).
                count = int(getattr(vl, "samples", 0) or 0) or int(options.render_samples)
                adaptive = adaptive_settings(
                    options.use_adaptive_sampling,
                    options.adaptive_threshold,
                    options.adaptive_min_samples,
                    options.time_limit,
                    count,
                )
                label = f"Penumbra | {layer}{' | ' + view if view else ''}"

                def on_sample(done, index=index, count=count, label=label):
                    self.update_stats("", f"{label} | Sample {done}/{count}")
                    self.update_progress((index + done / count) / len(views))
                    return not self.break_requested()

                out = self.render_frame(
                    depsgraph,
                    camera,
                    width,
                    height,
                    r.resolution_percentage / 100.0,
                    aux,
                    samples=(0, count),
                    sample_count=count,
                    on_sample=on_sample,
                    emission=vl.use_pass_emit,
                    adaptive=adaptive,
                    motion=motion,
                    passes=drawn_passes(requested_passes(vl)),
                    cryptomatte=cryptomatte_request(vl),
                )
                if vl.use_pass_vector and out.passes:
                    out.passes["VECTOR"] = self._vector_pass(out, camera, neighbours, width, height)
                if out.stats.cancelled and out.stats.samples == 0:
                    return  # cancelled before a sample was drawn: nothing to write
                self._report_frame(out.stats, label, count, reported)
                passes = self._passes(depsgraph, camera, out, window)
                self._write_result(window, layer, view, passes, cryptomatte_metadata(vl, out))
                self.update_progress((index + 1) / len(views))
                if out.stats.cancelled:
                    return  # the later views are not started
        except Exception as exc:  # a render must end with a message, never a crash
            traceback.print_exc(file=sys.stderr)
            self.report({"ERROR"}, f"Penumbra: render failed: {exc}")
        finally:
            # A final-render engine instance renders one frame; free while the context lives.
            self.free_gpu()
            self.texture_pool.end_render()  # the pool keeps what this frame used, no more

    def _view_camera(self, depsgraph, view, width, height):
        """The scene camera of ``view`` (a multiview render's, made the active view; "" for
        the one view of a mono render)."""
        scene = depsgraph.scene
        if not view:
            return camera_from_scene(depsgraph, scene, width, height)
        self.active_view_set(view)
        return camera_from_scene(
            depsgraph,
            scene,
            width,
            height,
            matrix_world=self.camera_model_matrix(scene.camera),
            shift_x=self.camera_shift_x(scene.camera),
        )

    def _report_frame(self, stats, label, count, reported):
        """What a view's frame tells the user: where it stopped early, its debug view's legend
        and its messages, each once a render (``reported``)."""
        if stats.stopped or stats.cancelled:
            # Esc (test_break) keeps what was rendered, as Cycles does: the samples drawn so
            # far, resolved and through the post stack, are this view's result.
            why = "Cancelled" if stats.cancelled else STOPPED[stats.stopped]
            stopped = f"Sample {stats.samples}/{count} | {why}"
            self.update_stats("", f"{label} | {stopped}")
            self.report({"INFO"}, f"Penumbra: {label[11:]}: {stopped}")
        legend = stats.debug_legend
        if legend and legend not in reported:  # what a debug view's colours mean
            reported.add(legend)
            self.report({"INFO"}, f"Penumbra debug view {legend}")
        for message in stats.messages:
            if message not in reported:
                reported.add(message)
                self.report({"WARNING"}, message)

    def _passes(self, depsgraph, camera, out, window):
        """{pass name: pixels} the view layer asks for, of the frame ``out``, cut to ``window``."""
        vl = depsgraph.view_layer
        width, height = self.resolution_x, self.resolution_y
        passes = {"Combined": window.cut(out.color_array())}
        if vl.use_pass_z:
            passes["Depth"] = window.cut(out.depth_array())
        if vl.penumbra.use_pass_shadow:
            passes["Shadow"] = window.cut(out.shadow_array())
        if vl.penumbra.use_pass_lit:
            passes["Lit"] = window.cut(out.lit_array())
        if vl.use_pass_normal:
            passes["Normal"] = window.cut(out.normal_array())
        if vl.use_pass_mist:
            passes["Mist"] = window.cut(self._mist(depsgraph.scene, camera, out, width, height))
        if vl.use_pass_emit:
            passes[EMISSION_PASS] = window.cut(out.emission_array())
        passes.update({name: window.cut(data) for name, data in further_pass_data(vl, out).items()})
        return passes

    @staticmethod
    def _mist(scene, camera, out, width, height):
        """The Mist pass from the Depth target and the world's mist settings."""
        scale = view_distance_scale(camera.projection, camera.is_ortho, width, height)
        depth = out.depth_array().astype(np.float64)
        depth[depth >= 1e9] = np.inf  # the background is beyond any mist
        mist = scene.world.mist_settings if scene.world is not None else None
        if mist is None:
            return np.where(np.isfinite(depth), 0.0, 1.0).astype(np.float32)
        return mist_pass(depth, scale, mist.start, mist.depth, mist.falloff)

    def _write_result(self, window, layer, view, passes, metadata=None):
        """Fill one result (``window``-sized, of ``layer`` and ``view``) with every pass the
        view layer has, and ``metadata`` ({key: value}: Cryptomatte's manifest) in the render's
        stamp data (written into the file's header); on any error the result is cancelled, not
        left half-written."""
        if metadata:
            # Into the render's own result (``get_result``), as Cycles stamps it: what a tile's
            # result holds is not merged into it, nor written to the file.
            final = self.get_result()
            for key, value in metadata.items():
                final.stamp_data_add_field(key, value)
        result = self.begin_result(0, 0, window.width, window.height, layer=layer, view=view)
        try:
            render_layer = result.layers[0]
            for name, data in passes.items():
                render_pass = render_layer.passes.find_by_name(name, view)
                if render_pass is not None:
                    render_pass.rect.foreach_set(np.ascontiguousarray(data, np.float32).ravel())
        except BaseException:
            self.end_result(result, cancel=True)
            raise
        self.end_result(result)

    # --- viewport -------------------------------------------------------------------------

    def view_update(self, context, depsgraph):
        self.cache.apply_updates(depsgraph)
        self.scene_changed()

    def view_draw(self, context, depsgraph):
        region = context.region
        rv3d = context.region_data
        width, height = region.width, region.height
        try:
            # Camera view: the scene camera's depth of field, refined as samples arrive.
            lens = None
            scene = depsgraph.scene
            if rv3d.view_perspective == "CAMERA" and scene.camera is not None:
                lens = camera_lens(scene.camera.evaluated_get(depsgraph), matrix_np(rv3d.view_matrix))
            out, _rendered = self.viewport_frame(
                depsgraph, rv3d.view_matrix, rv3d.window_matrix, width, height, lens=lens
            )
        except Exception as exc:
            message = f"Penumbra: viewport draw failed: {exc}"
            if message != self._reported:  # once per distinct error, not every redraw
                traceback.print_exc(file=sys.stderr)
                self._reported = message
            self.update_stats("", message)  # shown in the viewport's text overlay
            return
        self._reported = None
        # What the final render would put in its report (lights left out, clamped maps) shows
        # in the viewport's text overlay, as Blender's engines show their status there.
        # A debug view says what its colours mean there too.
        status = [self.viewport_status(), out.stats.debug_legend, *out.stats.messages]
        self.update_stats("", " | ".join(t for t in status if t))
        window = self.viewport_region(context, depsgraph, width, height)
        if window is not None:  # an empty render region shows nothing
            self.draw_display(depsgraph.scene, out.color, width, height, window)
        if self.refining():
            self.tag_redraw()  # the next redraw refines: full resolution, or one more sample


def further_passes(view_layer):
    """(name, channels, chan_id, type) of each further pass ``view_layer`` asks for, as
    Blender's engines register them (``output.FURTHER_PASSES``, Denoising Data, Shader AOVs,
    Cryptomatte's layers)."""
    new = bpy.app.version >= (5, 0, 0)
    keys = requested_passes(view_layer)
    out = [(pass_name(p, new), *p[4:]) for p in FURTHER_PASSES if p[1] in keys]
    out += [p[1:] for p in DENOISING_PASSES if p[0] in keys]
    for key in keys:
        if key.startswith("AOV_"):
            kind, name = key[4:].split(":", 1)
            out.append((name, 1, "X", "VALUE") if kind == "VALUE" else (name, 4, "RGBA", "COLOR"))
    out += [(f"Combined_{k[11:]}", 3, "RGB", "COLOR") for k in keys if k.startswith("LIGHTGROUP:")]
    levels = cryptomatte_levels(view_layer)
    for kind, switch in zip(cryptomatte.KINDS, CRYPTOMATTE_SWITCHES, strict=True):
        if getattr(view_layer, switch, False):
            out += [(f"Crypto{kind}{i:02d}", 4, "rgba", "COLOR") for i in range((levels + 1) // 2)]
    return out


def cryptomatte_request(view_layer):
    """``FrameRequest.cryptomatte`` of ``view_layer``: its levels and the kinds it asks for."""
    kinds = tuple(i for i, switch in enumerate(CRYPTOMATTE_SWITCHES) if getattr(view_layer, switch, False))
    return cryptomatte_levels(view_layer), kinds


def further_pass_data(view_layer, out):
    """{pass name: full-frame pixels} of the further passes of frame ``out``."""
    if not out.passes:
        return {}
    new = bpy.app.version >= (5, 0, 0)
    asked = requested_passes(view_layer)
    data = {}
    for p in FURTHER_PASSES:
        if p[1] in out.passes and p[1] in asked:
            pixels = out.passes[p[1]] if p[1] == "VECTOR" else out.pass_array(p[1], p[4])
            if p[1] in LIGHT_COLOR:
                pixels = divided(pixels, out.pass_array(LIGHT_COLOR[p[1]], 3))
            data[pass_name(p, new)] = pixels
    for key, name, channels, *_rest in DENOISING_PASSES:
        if key in out.passes:
            data[name] = out.pass_array(key, channels)
    for key in out.passes:
        if key.startswith("LIGHTGROUP:") and key in asked:
            data[f"Combined_{key[11:]}"] = out.pass_array(key, 3)
        if key.startswith("AOV_"):
            kind, name = key[4:].split(":", 1)
            data[name] = out.pass_array(key, 1 if kind == "VALUE" else 4)
            if kind == "COLOR":
                data[name][..., 3] = 1.0
    crypto = out.passes.get("CRYPTOMATTE")
    if crypto is not None:
        levels = cryptomatte_levels(view_layer)
        for index, (kind, switch) in enumerate(zip(cryptomatte.KINDS, CRYPTOMATTE_SWITCHES, strict=True)):
            if getattr(view_layer, switch, False):
                for i, layer in enumerate(crypto.layers(index, levels)):
                    data[f"Crypto{kind}{i:02d}"] = layer
    return data


def cryptomatte_metadata(view_layer, out):
    """The render result's Cryptomatte metadata of frame ``out`` (its manifests), or {}."""
    crypto = (out.passes or {}).get("CRYPTOMATTE")
    if crypto is None:
        return {}
    meta = {}
    for index, (kind, switch) in enumerate(zip(cryptomatte.KINDS, CRYPTOMATTE_SWITCHES, strict=True)):
        if getattr(view_layer, switch, False):
            meta.update(cryptomatte.metadata(view_layer.name, kind, crypto.names[index]))
    return meta


def motion_shapes(depsgraph, names):
    """{``motion_key``: (object name, ``motion.Shape``)} of the instances of the meshes
    ``names`` (full names) at the depsgraph's time."""
    from .frame.motion import Shape
    from .scene.extract import motion_key

    out = {}
    for inst in depsgraph.object_instances:
        ob = inst.object
        orig = ob.original if ob.original is not None else ob
        if ob.type != "MESH" or orig.name_full not in names:
            continue
        mesh = ob.data
        nv, nc = len(mesh.vertices), len(mesh.loops)
        co = np.empty(nv * 3, np.float32)
        mesh.vertices.foreach_get("co", co)
        vn = np.empty(nv * 3, np.float32)
        mesh.vertex_normals.foreach_get("vector", vn)
        cv = np.empty(nc, np.int32)
        mesh.loops.foreach_get("vertex_index", cv)
        cn = None
        if mesh.normals_domain != "POINT":
            cn = np.empty(nc * 3, np.float32)
            mesh.corner_normals.foreach_get("vector", cn)
            cn = cn.reshape(-1, 3)
        out[motion_key(inst)] = (orig.name, Shape(co.reshape(-1, 3), vn.reshape(-1, 3), cn, cv))
    return out


def deforming_shapes(steps):
    """From ``motion_shapes`` at each step: ({``motion_key``: [``Shape`` per step]} of the
    meshes that change shape and keep their topology, the names of those whose topology
    changes)."""
    from .frame.motion import same_topology

    if not steps or not steps[0]:
        return {}, []
    shapes, changing = {}, set()
    for key in set(steps[0]).intersection(*steps[1:]):
        name = steps[0][key][0]
        per_step = [s[key][1] for s in steps]
        if not same_topology(per_step):
            changing.add(name)
        elif any(not np.array_equal(per_step[0].positions, s.positions) for s in per_step[1:]):
            shapes[key] = per_step
    changing |= {v[0] for s in steps for k, v in s.items() if any(k not in o for o in steps)}
    return shapes, sorted(changing)


def _camera_view(cam_ob):
    """A camera object's world -> view matrix, its scale ignored (as ``camera_from_scene``)."""
    world = cam_ob.matrix_world
    if any(abs(world.col[i].xyz.length - 1.0) > 1e-6 for i in range(3)):
        world = world.normalized()
    return matrix_np(world.inverted_safe())


def _shutter_curve(mapping, points):
    """Render > Motion Blur > Shutter Curve at ``points`` even fractions of the shutter, or
    None where it is flat (every time weighs the same)."""
    try:
        mapping.initialize()
        values = tuple(float(mapping.evaluate(mapping.curves[0], k / (points - 1))) for k in range(points))
    except (AttributeError, IndexError, RuntimeError, TypeError):
        return None
    return None if max(values) - min(values) < 1e-6 else values


def _deforms(ob, scene):
    try:
        return bool(ob.is_deform_modified(scene, "RENDER"))
    except (AttributeError, TypeError, RuntimeError):
        return False


def _gpu_texture_limit():
    import gpu

    return gpu.capabilities.max_texture_size_get()


def register():
    bpy.utils.register_class(PenumbraRenderEngine)
    store.register()


def unregister():
    store.unregister()  # what final renders kept (meshes, their batches) is let go
    bpy.utils.unregister_class(PenumbraRenderEngine)
    gpu_pool.clear()  # Blender unregisters add-ons on exit, before its GPU module
