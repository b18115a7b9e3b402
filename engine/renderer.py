"""One frame as its stages: extract (done by the caller) -> shadows -> lit -> post -> output.
The same code serves the viewport and final renders; only where the camera comes from and
where the result goes differ.
"""

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from . import gpu_pool, kernels, light_bins, lightspace, sampling, simplify
from .frame_data import build_frame_data, select_lights
from .gpu_pool import new_texture
from .materials import CHANNELS, EXTENSION, INTERPOLATION, Material
from .post import post_stack
from .post.base import PostContext
from .programs import (
    BACKGROUND,
    JITTER_SIZE,
    MATERIAL_STRUCT,
    MAX_LIGHTS,
    MAX_SHADOW_TILES,
    SCALED_COPY,
    SCALED_COPY_SHADOW,
    SHADOW_SAMPLER,
    lit_program,
)
from .shadows import Density, ShadowAtlas, plan_shadows
from .textures import TextureCache

_UNSET = object()
DEFAULT_MATERIAL = Material()  # for faces whose material slot is empty
# Closed meshes (``extract.closed_outward``) seen from outside their bounds are drawn without
# their back faces, in the lit pass and in shadow maps: those faces are hidden by the mesh's
# own front faces, so the image is the same and the rasteriser sets up half the triangles.
CULL_CLOSED = True
_CORNER_BITS = np.array([[i & 1, (i >> 1) & 1, (i >> 2) & 1] for i in range(8)], dtype=bool)  # box corners


@dataclass
class FrameStats:
    """What a frame did: read by tests and the benchmark ("model only what a scene requires")."""

    shadow_maps: int = 0  # maps drawn this frame
    shadow_maps_reused: int = 0  # maps whose fit and casters did not change: not redrawn
    shadow_texels: int = 0  # texels of the maps drawn (each its size squared: the depth pass's fill)
    passes: int = 0
    post_passes: int = 0
    post_layers: int = 0  # post layers drawn (consecutive point layers share one pass)
    draws: int = 0
    triangles: int = 0
    texture_bytes: int = 0
    shadow_bytes: int = 0  # the shadow atlas (and its one-tile scratch target, if any)
    shaders_compiled: int = 0
    samples: int = 0  # samples rendered by this call
    lights_sampled: int = 0  # lights that moved between samples (the others kept one map)
    cancelled: bool = False  # on_sample asked to stop before the last sample
    lights_out_of_view: int = 0  # lights that reach no visible surface: no map, no shading
    closed_culled: int = 0  # closed instances drawn without back faces (lit pass and each map)
    simplified: int = 0  # instances drawn at a level of detail (``simplify``; ``triangles`` counts its)
    binned: bool = False  # the lit pass looped over each screen bin's lights only
    messages: list = field(default_factory=list)  # what the user must be told about this frame


@dataclass
class FrameOutput:
    color: object  # GPUTexture, scene-linear RGBA float
    depth: object  # GPUTexture, view-space distance along the camera axis
    shadow: object  # GPUTexture, fraction of direct light not blocked (1 for background)
    stats: FrameStats
    width: int
    height: int
    lit: object = None  # GPUTexture, the lit pass before the post stack
    normal: object = None  # GPUTexture, world-space shading normal (0 for the background)
    depth_data: object = None  # arrays of the centred sample when several were accumulated
    normal_data: object = None
    emission: object = None  # GPUTexture, the Emission pass (when asked for)

    def emission_array(self):
        return texture_array(self.emission, 4)[..., :3]

    def normal_array(self):
        if self.normal_data is not None:
            return self.normal_data[..., :3]
        return texture_array(self.normal, 4)[..., :3]

    def lit_array(self):
        return texture_array(self.lit, 4)

    def color_array(self):
        return texture_array(self.color, 4)

    def depth_array(self):
        if self.depth_data is not None:
            return self.depth_data
        return texture_array(self.depth, 1)[..., 0]

    def shadow_array(self):
        return texture_array(self.shadow, 1)[..., 0]


@dataclass
class Draw:
    """One mesh instance of the frame with its GPU batches."""

    instance: object  # extract.MeshInstance
    whole: object  # GPUBatch of every triangle (shadow passes)
    parts: list  # [(material index, GPUBatch)] (lit pass)
    model: object  # mathutils.Matrix
    det: float  # sign of the model matrix: flips the winding under negative scale
    identity: tuple  # what a shadow tile's content depends on
    corners: np.ndarray  # (8, 3) world corners of the instance's bounds
    closed: bool = False  # a closed opaque surface: back faces hidden from outside its bounds

    def material(self, index):
        materials = self.instance.materials
        mat = materials[index] if 0 <= index < len(materials) else None
        return mat or DEFAULT_MATERIAL


def buffer_array(buf):
    """A ``gpu.types.Buffer`` as a C-ordered numpy array of its dimensions.

    Blender 4.5's buffer protocol reports reversed strides, so ``np.asarray`` alone scrambles
    multi-dimensional data there; reading the memory in its own order is right on every line."""
    a = np.asarray(buf)
    return a.ravel(order="K").reshape(tuple(buf.dimensions))


def texture_array(texture, channels):
    """Read a float texture back as an array (height, width, channels), row 0 at the bottom."""
    return buffer_array(texture.read()).astype(np.float32, copy=False).reshape(texture.height, texture.width, channels)


class Renderer:
    """GPU state of one engine instance. Create and use only inside a GPU context."""

    def __init__(self, pool=None, shaders=None):
        """``pool``: a ``gpu_pool.TexturePool`` the frame's targets and shadow atlas come from
        (final renders); ``release`` gives them back. ``shaders``: a ``ShaderCache`` shared
        with other renderers (final renders), else one of its own."""
        from ..shaders.loader import ShaderCache

        self.pool = pool
        self.shaders = shaders if shaders is not None else ShaderCache()
        self.shadows = ShadowAtlas(pool)
        self.post = post_stack()
        self._batches = {}  # (geometry key, serial) -> (whole, parts)
        self._lod_batches = {}  # (geometry key, serial, level) -> (whole, parts) of ``simplify.simplified``
        self.textures = TextureCache(gpu_pool.FINAL_IMAGES if pool is not None else None)
        self._material_ubos = {}  # id(Material) -> (Material, GPUUniformBuf)
        self._jitter_tex = None
        self._jitter_dummy = None
        self._size = None
        self._color = self._depth = self._shadow = self._normal = self._zbuffer = None
        self._fb = self._fb_color = None
        self._post_ctx = None
        self._ubos = {}
        self._dummy_shadow = None
        self._bins_tex = None
        self._accum_color = self._accum_shadow = self._accum_fb = self._resolve_fb = None
        self._fullscreen_batch = None
        self._weight_sum = 0.0
        self._centre = None  # (depth, normal) arrays of a multi-sample frame's centred sample
        self._emission = self._fb_emit = self._emission_targets = None
        self._emission_on = False
        self._depth_range = _UNSET  # the frame's visible depth range, once computed
        self._origin = np.zeros(3)  # the frame origin (``render``): positions reach the GPU relative to it
        self._receivers = None  # and what the camera sees (lightspace.visible_receivers)

    # --- the frame ------------------------------------------------------------------------

    def render(
        self,
        snapshot,
        camera,
        settings,
        width,
        height,
        aux=True,
        samples=(0, 1),
        sample_count=1,
        on_sample=None,
        emission=False,
    ):
        """Samples ``samples[0] .. samples[1] - 1`` of a frame of ``sample_count`` samples
        (``engine/sampling.py``), added to the samples this renderer already accumulated for
        it (a start of 0 begins the frame afresh), then the post stack on their filtered
        average. One sample of one is exactly the single-sample frame, with no accumulation.
        ``aux``: also write the depth, shadow and normal targets (a final render's passes;
        depth and normal are the centred sample's, shadow is averaged like colour).
        ``on_sample(done)`` after each sample; returning False stops the frame there (cancel).
        ``emission`` (with ``aux``): also write the Emission pass's target, averaged like colour."""
        stats = FrameStats()
        compiled_before = self.shaders.compiled
        self._depth_range = _UNSET
        emission = bool(emission and aux)
        self._emission_on = emission
        self._ensure_targets(width, height, aux, emission)
        # The frame origin: the GPU gets every position relative to the camera (model matrices,
        # lights, the camera's and each map's view), computed here in float64, so a scene far
        # from the world origin keeps float32's precision where it is seen. Maps do not depend
        # on it (each is drawn and read through the same shift) and stay reusable when it moves.
        origin = camera.position
        self._origin = origin if np.all(np.isfinite(origin)) else np.zeros(3)
        draws = self._draw_list(snapshot, stats, camera, settings, (width, height))
        stats.messages.extend(getattr(snapshot, "messages", ()))
        self.textures.forget(getattr(snapshot, "images_changed", ()))
        lights = select_lights(snapshot.lights, camera.position, MAX_LIGHTS)
        if len(lights) < len(snapshot.lights):
            stats.messages.append(
                f"Penumbra: {len(snapshot.lights)} lights; only the {MAX_LIGHTS} that contribute most to the view "
                "are lit"
            )
        start, stop = samples
        accumulate = sample_count > 1
        if accumulate:
            self._ensure_accumulation(aux)
            if start == 0:
                self._accum_color.clear(format="FLOAT", value=(0.0, 0.0, 0.0, 0.0))
                if self._accum_shadow is not None:
                    self._accum_shadow.clear(format="FLOAT", value=(0.0,))
                if emission:
                    self._emission_accumulation().clear(format="FLOAT", value=(0.0, 0.0, 0.0, 0.0))
                self._weight_sum = 0.0
        plan = None
        moving = sampling.sampled_lights(lights, self._plan(draws, lights, camera, settings)) if accumulate else set()
        stats.lights_sampled = len(moving)
        for s in range(start, stop):
            dx, dy, weight = sampling.pixel_offset(s, settings.filter_size) if accumulate else (0.0, 0.0, 1.0)
            view_camera = camera
            if dx or dy:
                jittered = sampling.jittered_projection(camera.projection, dx, dy, width, height)
                view_camera = dataclasses.replace(camera, projection=jittered)
            sample_lights = [
                sampling.light_at_sample(lt, i, s, sample_count) if i in moving else lt for i, lt in enumerate(lights)
            ]
            alpha_offset = (s + 0.5) / sample_count if accumulate else 0.5
            plan = self._sample(draws, sample_lights, camera, view_camera, snapshot, settings, aux, stats, alpha_offset)
            if accumulate:
                self._accumulate(weight, aux)
                if emission:
                    accum, accum_fb, _resolve_fb = self._emission_targets
                    self._fullscreen(
                        SCALED_COPY, accum_fb, {"src_color": self._emission}, {"scale": weight}, "ADDITIVE_PREMULT"
                    )
                self._weight_sum += weight
            if aux and accumulate and s == 0:  # the centred sample's depth and normal
                self._centre = (texture_array(self._depth, 1)[..., 0].copy(), texture_array(self._normal, 4).copy())
            stats.samples += 1
            if on_sample is not None and on_sample(s + 1) is False:
                stats.cancelled = True
                break
        if accumulate and stats.samples:
            self._resolve(aux)
            if emission:
                accum, _accum_fb, resolve_fb = self._emission_targets
                inverse = 1.0 / self._weight_sum if self._weight_sum > 0.0 else 0.0
                self._fullscreen(SCALED_COPY, resolve_fb, {"src_color": accum}, {"scale": inverse})
        color = self._post_pass(settings, stats)
        target_bytes = 16 + 4 + (4 + 4 + 8 if aux else 0)  # colour, z-buffer, depth, shadow, normal
        if accumulate:
            target_bytes += 16 + (4 if aux else 0)
        stats.shadow_bytes = self.shadows.memory_bytes if plan is not None and plan.tiles else 0
        stats.texture_bytes = (
            width * height * target_bytes + stats.shadow_bytes + self._post_ctx.memory_bytes + self.textures.bytes
        )
        stats.shaders_compiled = self.shaders.compiled - compiled_before
        if not aux:
            return FrameOutput(color, None, None, stats, width, height, lit=self._color)
        out = FrameOutput(color, self._depth, self._shadow, stats, width, height, lit=self._color, normal=self._normal)
        out.emission = self._emission if emission else None
        if accumulate and self._centre is not None:
            out.depth_data, out.normal_data = self._centre
        return out

    def _sample(self, draws, lights, camera, view_camera, snapshot, settings, aux, stats, alpha_offset=0.5):
        """One sample: shadow maps (planned from the unjittered ``camera``, so a light that
        does not move between samples keeps its map), then the lit pass seen through
        ``view_camera``. Returns the shadow plan."""
        width, height = self._size
        lights, rects = self._lights_in_view(lights, draws, view_camera, width, height, stats)
        plan = self._shadow_pass(draws, lights, camera, settings, stats, alpha_offset)
        depth_range = self._depth_range
        if depth_range is _UNSET:  # no shadow plan this frame: the quick, wider bound
            corners = np.stack([d.corners for d in draws]) if draws else np.zeros((0, 8, 3))
            depth_range = lightspace.box_depth_range(camera.projection, camera.view, corners, camera.is_ortho)
        # The lit pass rasterises with the depth buffer spread over what the camera sees.
        fitted = lightspace.depth_fitted(view_camera.projection, view_camera.is_ortho, depth_range)
        raster_camera = (
            view_camera if fitted is view_camera.projection else dataclasses.replace(view_camera, projection=fitted)
        )
        data = build_frame_data(
            lights,
            raster_camera,
            snapshot.world if snapshot.world is not None else snapshot.world_color,
            settings,
            plan,
            tile_size=self.shadows.size if plan.tiles else 1,
            atlas_columns=self.shadows.columns if plan.tiles else 1,
            depth_format=self.shadows.depth_format if plan.tiles else "FLOAT32",
            aux_outputs=aux,
            rects=rects,
            size=(width, height),
            alpha_offset=alpha_offset,
            origin=self._origin,
        )
        stats.binned = data.bins is not None
        seen = [d for d in draws if d.instance.camera]
        masks = self._light_masks(seen, lights, data.order) if data.defines.get("LIGHT_LINKING") else None
        self._lit_pass(seen, view_camera, data, plan, snapshot.world_color, settings, aux, stats, snapshot.world, masks)
        return plan

    @staticmethod
    def _light_masks(draws, lights, order):
        """Light linking: per draw (by id), the lit pass's ``light_mask``: bit j of word j // 32
        set when light ``order[j]`` (the j-th light as the lit pass walks them) reaches it."""
        by_names = {}  # instances of one object share its mask
        out = {}
        for d in draws:
            names = d.instance.names
            if names not in by_names:
                words = [0, 0, 0, 0]
                for j, i in enumerate(order):
                    receivers = lights[i].receivers
                    if receivers is None or receivers.links(names):
                        words[j >> 5] |= 1 << (j & 31)
                by_names[names] = tuple(w - (1 << 32) if w >= 1 << 31 else w for w in words)  # as signed ints
            out[id(d)] = by_names[names]
        return out

    # --- stages ---------------------------------------------------------------------------

    def _draw_list(self, snapshot, stats, camera=None, settings=None, size=None):
        """The frame's instances with their batches; batches of geometry no longer in the
        snapshot are released. Per-instance numbers (sign of the matrix, world bounds, level
        of detail) are computed for all instances at once."""
        from mathutils import Matrix

        kept = [(inst, snapshot.geometry[inst.key]) for inst in snapshot.instances if inst.key in snapshot.geometry]
        draws = []
        used_levels = set()
        if kept:
            matrices = np.stack([inst.matrix for inst, _geo in kept])
            bounds = np.stack([geo.bounds for _inst, geo in kept])
            dets = np.linalg.det(matrices[:, :3, :3])
            local = np.where(_CORNER_BITS[None], bounds[:, None, 1], bounds[:, None, 0])  # (n, 8, 3)
            corners = np.einsum("nij,nkj->nki", matrices[:, :3, :3], local) + matrices[:, None, :3, 3]
            levels = self._levels(kept, matrices, bounds, corners, camera, settings, size)
            for i, (inst, geo) in enumerate(kept):
                lod = simplify.simplified(geo, levels[i]) if levels[i] is not None else None
                if lod is not None:
                    used_levels.add((inst.key, geo.serial, levels[i]))
                    whole, parts = self._batches_for((inst.key, geo.serial, levels[i]), lod, self._lod_batches)
                    identity = (inst.key, inst.matrix.tobytes(), geo.serial, levels[i])
                    stats.simplified += 1
                else:
                    whole, parts = self._batches_for(inst.key, geo)
                    identity = (inst.key, inst.matrix.tobytes(), geo.serial)
                model = inst.matrix.copy()
                model[:3, 3] -= self._origin
                model = Matrix(model.tolist())
                draw = Draw(inst, whole, parts, model, float(dets[i]), identity, corners[i])
                closed = CULL_CLOSED and geo.closed and lod is None  # a level is not tested for closedness
                draw.closed = closed and not any(draw.material(m).uses_alpha for m, _b in parts)
                draws.append(draw)
                stats.triangles += (lod or geo).triangle_count
        live = {(key, geo.serial) for key, geo in snapshot.geometry.items()}
        for stale in [k for k in self._batches if k not in live]:
            del self._batches[stale]
        for stale in [k for k in self._lod_batches if k not in used_levels]:  # levels this frame did not draw
            del self._lod_batches[stale]
        return draws

    def _levels(self, kept, matrices, bounds, corners, camera, settings, size):
        """Each instance's level of detail (``simplify.level_for``) or None (drawn whole):
        with Render › Simplify on, its Penumbra › Merge Below in pixels of the full-resolution
        frame, at the instance's nearest point to the camera."""
        levels = [None] * len(kept)
        if not getattr(settings, "use_simplify", False):
            return levels
        pixels = float(settings.simplify_pixels) * float(settings.pixel_scale)
        if not pixels > 0.0 or camera is None or size is None:
            return levels
        footprint = lightspace.pixel_footprint(camera.projection, camera.is_ortho, *size)
        view = np.asarray(camera.view, dtype=np.float64)
        vp = np.asarray(camera.projection, dtype=np.float64) @ view
        near = vp[2] + vp[3]  # clip z + w: positive beyond the near plane
        beyond = np.all(corners @ near[:3] + near[3] > 0.0, axis=1)
        nearest = np.min(-(corners @ view[2, :3] + view[2, 3]), axis=1)
        stretch = np.linalg.svd(matrices[:, :3, :3], compute_uv=False)[:, 0]
        extent = np.max(bounds[:, 1] - bounds[:, 0], axis=1)
        for i, (inst, geo) in enumerate(kept):
            if not beyond[i] or geo.triangle_count < simplify.MIN_TRIANGLES:
                continue
            if geo.uvs is not None or geo.colors is not None or geo.tangents is not None:
                continue  # its materials read more than positions and normals
            if any(m is not None and m.uses_alpha for m in inst.materials):
                continue
            levels[i] = simplify.level_for(float(extent[i]), float(stretch[i]), float(nearest[i]), footprint, pixels)
        return levels

    def _lights_in_view(self, lights, draws, camera, width, height, stats):
        """The lights that can light a visible surface, with the screen rectangle each can
        reach (``light_bins.screen_rects``); a light that reaches nothing the camera sees gets
        no shadow map and no shading."""
        if not draws or not lights:
            return lights, None
        corners = np.concatenate([d.corners for d in draws])
        lo, hi = corners.min(axis=0), corners.max(axis=0)
        rects = light_bins.screen_rects(lights, camera.projection @ camera.view, lo, hi, width, height)
        keep = [i for i, r in enumerate(rects) if r is not None]
        stats.lights_out_of_view = len(lights) - len(keep)
        return [lights[i] for i in keep], [rects[i] for i in keep]

    def _plan(self, draws, lights, camera, settings, map_size=None):
        """The shadow plan of ``lights`` (numpy only, nothing drawn), with maps of
        ``map_size`` (default: the setting)."""
        corners = np.stack([d.corners for d in draws]) if draws else np.zeros((0, 8, 3))
        view_corners = _view_corners(camera) if settings.shadow_sun_fit == "VIEW" else None
        size = max(1, int(settings.shadow_map_size)) if map_size is None else map_size
        if self._depth_range is _UNSET:
            # The visible depth range and the visible receivers depend only on the unjittered
            # camera and the instances' bounds: once per frame, not per sample.
            self._depth_range = lightspace.view_depth_range(camera.projection, camera.view, corners, camera.is_ortho)
            self._receivers = lightspace.visible_receivers(corners, camera.projection @ camera.view)
        return plan_shadows(
            lights,
            corners,
            size,
            view_corners,
            camera,
            int(settings.shadow_cascades),
            self._depth_range,
            kernel=_fixed_kernel(settings),
            pcss=settings.shadow_filter == "PCSS",
            receivers=self._receivers,
            density=self._density(camera, settings),
        )

    def _density(self, camera, settings):
        """How finely this frame's camera sees (``shadows.Density``), or None when maps keep
        their full size (Texels per Pixel 0)."""
        per_pixel = float(settings.shadow_texels_per_pixel)
        if not per_pixel > 0.0 or self._size is None:
            return None
        per_depth, constant = lightspace.pixel_footprint(camera.projection, camera.is_ortho, *self._size)
        return Density(np.asarray(camera.view, dtype=np.float64), per_depth, constant, per_pixel)

    def _shadow_pass(self, draws, lights, camera, settings, stats, alpha_offset=0.5):
        """Plan the maps this frame needs (numpy) and draw the ones whose content changed."""
        map_size = max(1, int(settings.shadow_map_size))
        plan = self._plan(draws, lights, camera, settings, map_size)
        if not plan.tiles:
            return plan
        columns, _rows = self.shadows.grid(len(plan.tiles))
        clamped = min(map_size, _gpu_texture_limit() // columns)
        if max(t.size for t in plan.tiles) > clamped:
            stats.messages.append(
                f"Penumbra: shadow map size {map_size} clamped to {clamped}: {len(plan.tiles)} maps share this "
                "GPU's largest texture"
            )
            map_size = clamped
            plan = self._plan(draws, lights, camera, settings, map_size)
        if plan.unshadowed:
            stats.messages.append(
                f"Penumbra: {plan.unshadowed} light(s) left unshadowed: more than {MAX_SHADOW_TILES} shadow maps"
            )
        for i, entry in plan.lights.items():  # shadow linking: only the light's blockers cast
            blockers = lights[i].blockers
            if blockers is not None:
                for t in entry.tiles:
                    if t >= 0:
                        tile = plan.tiles[t]
                        tile.casters = np.array(
                            [c for c in tile.casters if blockers.links(draws[c].instance.names)], dtype=np.int64
                        )
        self.shadows.place(plan, settings.shadow_depth_format)
        shadow_draws = [self._caster(d) for d in draws]
        self.shadows.render(
            plan, shadow_draws, self.shaders, settings.shadow_cull_front, stats, alpha_offset, self._origin
        )
        return plan

    def _caster(self, d):
        """What instance ``d`` draws into shadow maps (``shadows.Caster``), or None when it
        casts no shadow (Ray Visibility > Shadow off). Parts with alpha cover each map texel
        in a fraction alpha of the samples (``shadows.ShadowAtlas.render``)."""
        from .shadows import Caster

        if not d.instance.shadow:
            return None
        mats = [(index, batch, d.material(index)) for index, batch in d.parts]
        cull = bool(mats) and all(m.cull_shadow for _i, _b, m in mats)
        # Material > Settings > Transparent Shadows off: its alpha casts as an opaque surface.
        if not any(m.uses_alpha and m.transparent_shadow for _i, _b, m in mats):
            return Caster([d.whole], d.model, d.det, d.identity, cull_back=cull, closed=d.closed, corners=d.corners)
        solid, cutouts = [], []
        for _index, batch, mat in mats:
            if not (mat.uses_alpha and mat.transparent_shadow):
                solid.append(batch)
            elif "alpha" in mat.textures:
                cutouts.append((batch, self._material_ubo(mat), self.textures.get(mat.textures["alpha"].image)))
            elif mat.alpha > 0.0:
                cutouts.append((batch, self._material_ubo(mat), None))
        identity = (*d.identity, tuple(id(m) for _i, _b, m in mats))
        return Caster(solid, d.model, d.det, identity, cutouts, cull_back=cull)

    def _material_ubo(self, mat):
        """The MaterialData block of ``mat``, built once per Material read."""
        import gpu

        cached = self._material_ubos.get(id(mat))
        if cached is not None and cached[0] is mat:
            return cached[1]
        row = {
            "base_color": tuple(mat.base_color)[:4],
            "emission": tuple(mat.emission)[:3],
            "roughness": float(mat.roughness),
            "metallic": float(mat.metallic),
            "specular": float(mat.specular),
            "alpha": float(mat.alpha),
            "normal_strength": float(mat.normal_strength),
        }
        for channel in CHANNELS:
            ref = mat.textures.get(channel)
            rows = ref.transform if ref is not None else ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0))
            row[f"{channel}_uv_u"] = (*rows[0], 0.0)
            row[f"{channel}_uv_v"] = (*rows[1], 0.0)
            mode = (0, 0, 0, 0)
            if ref is not None:
                mode = (
                    INTERPOLATION.get(ref.interpolation, 1),
                    EXTENSION.get(ref.extension, 0),
                    int(ref.output == "Alpha"),
                    int(ref.component),
                )
            row[f"{channel}_mode"] = mode
        ubo = gpu.types.GPUUniformBuf(MATERIAL_STRUCT.pack([row]).tobytes())
        if len(self._material_ubos) > 4096:
            self._material_ubos.clear()
        self._material_ubos[id(mat)] = (mat, ubo)
        return ubo

    def _lit_pass(self, draws, camera, data, plan, world_color, settings, aux, stats, world=None, masks=None):
        """Every visible part, grouped by material variant: opaque and alpha-hashed parts
        nearest first, then alpha-blended parts farthest first, blended over them (their
        depth, normal and shadow stay those of what is behind; EEVEE too keeps blended
        surfaces out of its depth)."""
        import gpu

        shadow_tex = self.shadows.texture if plan.tiles else self._shadow_dummy()
        # Transparent film: the background is RGBA 0 (premultiplied), as Blender's engines write it.
        bg = (0.0, 0.0, 0.0, 0.0) if settings.film_transparent else (*map(float, world_color[:3]), 1.0)
        self._color.clear(format="FLOAT", value=bg)
        if aux:
            # The second attachment holds view distance; the background is "infinitely" far, as
            # in Blender's own Depth pass.
            self._depth.clear(format="FLOAT", value=(1e10,))
            self._shadow.clear(format="FLOAT", value=(1.0,))
            self._normal.clear(format="FLOAT", value=(0.0, 0.0, 0.0, 0.0))
        if world is not None and world.image is not None and not settings.film_transparent:
            self._background(world, camera)
        # Closed instances wholly beyond the near plane: from there no back face shows.
        outside = set()
        closed = [d for d in draws if d.closed]
        if closed:
            vp = camera.projection @ camera.view
            near = vp[2] + vp[3]  # clip z + w: positive beyond the near plane
            beyond = np.all(np.stack([d.corners for d in closed]) @ near[:3] + near[3] > 0.0, axis=1)
            outside = {id(d) for d, ok in zip(closed, beyond, strict=True) if ok}
            stats.closed_culled += len(outside)
        opaque, blended = [], []
        for rank, d in enumerate(_front_to_back(draws, camera)):
            for mat_index, batch in d.parts:
                mat = d.material(mat_index)
                features = mat.features | ({"HOLDOUT"} if d.instance.holdout else set())
                entry = (features, rank, d, batch, mat)
                (blended if "ALPHA_BLEND" in features and not d.instance.holdout else opaque).append(entry)
        opaque.sort(key=lambda e: (sorted(e[0]), e[1]))
        blended.sort(key=lambda e: -e[1])
        width, height = self._size
        bound = {"shader": None}

        emission = aux and getattr(self, "_emission_on", False)
        if emission:
            self._emission.clear(format="FLOAT", value=(0.0, 0.0, 0.0, 0.0))

        def bind(features, with_aux):
            program = lit_program(frozenset(features), with_aux, emission and with_aux)
            shader = self.shaders.get(program, data.defines)
            if bound["shader"] is shader:
                return shader
            shader.bind()
            shader.uniform_block("frame", self._ubo("frame", data.frame))
            shader.uniform_block("lights", self._ubo("lights", data.lights))
            shader.uniform_block("shadow_tiles", self._ubo("tiles", data.tiles))
            shader.uniform_sampler(SHADOW_SAMPLER, shadow_tex)
            shader.uniform_sampler("jitter_tex", self._jitter(data.disk_samples))
            shader.uniform_sampler("light_bins", self._bins_texture(data.bins))
            bound["shader"] = shader
            return shader

        def draw(entries, with_aux):
            last = None
            for features, _rank, d, batch, mat in entries:
                # Material › Backface Culling › Camera: faces turned away are not drawn (the
                # winding flips under a mirroring model matrix).
                cull = mat.cull_camera or id(d) in outside
                culling = (cull, cull and d.det < 0.0)
                if bound.get("culling") != culling:
                    gpu.state.face_culling_set("BACK" if culling[0] else "NONE")
                    gpu.state.front_facing_set(culling[1])
                    bound["culling"] = culling
                shader = bind(features, with_aux)
                if last is not d or bound.get("model_shader") is not shader:
                    shader.uniform_float("model", d.model)
                    if masks is not None:
                        shader.uniform_int("light_mask", masks[id(d)])
                    last, bound["model_shader"] = d, shader
                shader.uniform_block("material", self._material_ubo(mat))
                for channel, ref in mat.textures.items():
                    shader.uniform_sampler(f"tex_{channel}", self.textures.get(ref.image))
                batch.draw(shader)
                stats.draws += 1

        fb = self._fb_emit if emission else (self._fb if aux else self._fb_color)
        with fb.bind():
            gpu.state.viewport_set(0, 0, width, height)
            fb.clear(depth=1.0)
            gpu.state.depth_test_set("LESS_EQUAL")
            gpu.state.depth_mask_set(True)
            draw(opaque, aux)
        if blended:
            bound["shader"] = None
            with self._fb_color.bind():
                gpu.state.viewport_set(0, 0, width, height)
                gpu.state.depth_test_set("LESS_EQUAL")
                gpu.state.depth_mask_set(False)
                gpu.state.blend_set("ALPHA_PREMULT")
                draw(blended, False)
                gpu.state.blend_set("NONE")
        gpu.state.face_culling_set("NONE")
        gpu.state.front_facing_set(False)
        gpu.state.depth_test_set("NONE")
        gpu.state.depth_mask_set(False)
        stats.passes += 1

    def _background(self, world, camera):
        """The world's Environment Texture behind the scene (``programs.BACKGROUND``)."""
        from mathutils import Matrix

        width, height = self._size
        try:
            inverse = np.linalg.inv(camera.projection @ camera.view @ lightspace.from_origin(self._origin))
        except np.linalg.LinAlgError:
            return
        if not np.all(np.isfinite(inverse)):
            return
        self._fullscreen(
            BACKGROUND,
            self._fb_color,
            {"env": self.textures.get(world.image)},
            {
                "inverse_view_proj": Matrix(inverse.tolist()),
                "viewport_origin": (0.0, 0.0),
                "viewport_size": (float(width), float(height)),
                "strength": float(world.strength),
            },
        )

    def _post_pass(self, settings, stats):
        ctx = self._post_ctx
        ctx.frame = settings.frame
        ctx.pixel_scale = settings.pixel_scale
        ctx.stats = stats
        return self.post.run(ctx, self._color, settings.layers)

    # --- resources ------------------------------------------------------------------------

    def release(self):
        """Give the frame's targets and the shadow atlas back to the pool: at the end of a
        final render, inside its GPU context. The renderer is not used again."""
        if self.pool is None:
            return
        accum = self._emission_targets[0] if self._emission_targets is not None else None
        self._fb = self._fb_color = self._fb_emit = self._accum_fb = self._resolve_fb = None
        self._emission_targets = None
        self.pool.give(
            [
                self._color,
                self._zbuffer,
                self._depth,
                self._shadow,
                self._normal,
                self._emission,
                self._accum_color,
                self._accum_shadow,
                accum,
            ]
        )
        self._color = self._zbuffer = self._depth = self._shadow = self._normal = self._emission = None
        self._accum_color = self._accum_shadow = None
        self._size = None
        if self._post_ctx is not None:
            self._post_ctx.release()
            self._post_ctx = None
        self.shadows.free()

    def _ensure_targets(self, width, height, aux, emission=False):
        """The lit pass's targets at this size; the auxiliary ones (depth, shadow, normal) only
        once a frame asks for them, the Emission pass's likewise."""
        import gpu

        if self._size != (width, height):
            self._color = new_texture(self.pool, (width, height), "RGBA32F")
            self._zbuffer = new_texture(self.pool, (width, height), "DEPTH_COMPONENT32F")
            self._fb_color = gpu.types.GPUFrameBuffer(depth_slot=self._zbuffer, color_slots=(self._color,))
            self._depth = self._shadow = self._normal = self._fb = None
            self._emission = self._fb_emit = self._emission_targets = None
            if self._post_ctx is not None:
                self._post_ctx.release()
            self._post_ctx = PostContext(self.shaders, width, height, texture_pool=self.pool)
            self._size = (width, height)
        if aux and self._fb is None:
            self._depth = new_texture(self.pool, (width, height), "R32F")
            self._shadow = new_texture(self.pool, (width, height), "R32F")
            self._normal = new_texture(self.pool, (width, height), "RGBA16F")
            self._fb = gpu.types.GPUFrameBuffer(
                depth_slot=self._zbuffer, color_slots=(self._color, self._depth, self._shadow, self._normal)
            )
        if emission and self._fb_emit is None:
            self._emission = new_texture(self.pool, (width, height), "RGBA32F")
            self._fb_emit = gpu.types.GPUFrameBuffer(
                depth_slot=self._zbuffer,
                color_slots=(self._color, self._depth, self._shadow, self._normal, self._emission),
            )

    def _emission_accumulation(self):
        """The Emission pass's accumulation target (and the framebuffers that add to it and
        resolve it into the pass's target), made on first use at this size."""
        import gpu

        if self._emission_targets is None:
            width, height = self._size
            accum = new_texture(self.pool, (width, height), "RGBA32F")
            self._emission_targets = (
                accum,
                gpu.types.GPUFrameBuffer(color_slots=(accum,)),
                gpu.types.GPUFrameBuffer(color_slots=(self._emission,)),
            )
        return self._emission_targets[0]

    def _ensure_accumulation(self, aux):
        """The float32 accumulation targets of a multi-sample frame (colour, and shadow for a
        final render's Shadow pass), and the targets their resolve writes."""
        import gpu

        width, height = self._size
        if self._accum_color is None or (self._accum_color.width, self._accum_color.height) != (width, height):
            self._accum_color = new_texture(self.pool, (width, height), "RGBA32F")
            self._accum_shadow = None
            self._accum_fb = gpu.types.GPUFrameBuffer(color_slots=(self._accum_color,))
        if aux and self._accum_shadow is None:
            self._accum_shadow = new_texture(self.pool, (width, height), "R32F")
            self._accum_fb = gpu.types.GPUFrameBuffer(color_slots=(self._accum_color, self._accum_shadow))
        self._centre = None

    def _fullscreen(self, program, framebuffer, samplers, uniforms, blend="NONE"):
        import gpu
        from gpu_extras.batch import batch_for_shader

        shader = self.shaders.get(program)
        if self._fullscreen_batch is None:
            self._fullscreen_batch = batch_for_shader(shader, "TRIS", {"pos": ((-1, -1), (3, -1), (-1, 3))})
        width, height = self._size
        with framebuffer.bind():
            gpu.state.viewport_set(0, 0, width, height)
            gpu.state.depth_test_set("NONE")
            gpu.state.blend_set(blend)
            shader.bind()
            for name, tex in samplers.items():
                shader.uniform_sampler(name, tex)
            if any(pc[1] == "origin" for pc in program.push_constants):
                shader.uniform_int("origin", (0, 0))
            for name, value in uniforms.items():
                shader.uniform_float(name, value)
            self._fullscreen_batch.draw(shader)
            gpu.state.blend_set("NONE")

    def _accumulate(self, weight, aux):
        """accumulation += weight * this sample (colour, and shadow with ``aux``)."""
        self._scaled_copy(self._accum_fb, (self._color, self._shadow), weight, aux, blend="ADDITIVE_PREMULT")

    def _resolve(self, aux):
        """The filtered average (accumulation / total weight) into the colour (and shadow)
        targets, which the post stack and the passes read as a single-sample frame's."""
        import gpu

        with_shadow = aux and self._accum_shadow is not None
        if self._resolve_fb is None or self._resolve_fb[0] != (self._size, with_shadow):
            slots = (self._color, self._shadow) if with_shadow else (self._color,)
            self._resolve_fb = ((self._size, with_shadow), gpu.types.GPUFrameBuffer(color_slots=slots))
        inverse = 1.0 / self._weight_sum if self._weight_sum > 0.0 else 0.0
        self._scaled_copy(self._resolve_fb[1], (self._accum_color, self._accum_shadow), inverse, aux)

    def _scaled_copy(self, framebuffer, sources, scale, aux, blend="NONE"):
        """framebuffer (<blend>)= scale * sources: colour, and shadow when ``aux`` and the
        accumulation carries it."""
        with_shadow = aux and self._accum_shadow is not None
        samplers = {"src_color": sources[0]}
        if with_shadow:
            samplers["src_shadow"] = sources[1]
        program = SCALED_COPY_SHADOW if with_shadow else SCALED_COPY
        self._fullscreen(program, framebuffer, samplers, {"scale": scale}, blend)

    def _ubo(self, name, data):
        import gpu

        raw = data.tobytes()
        ubo = self._ubos.get(name)
        if ubo is None or ubo[1] != len(raw):
            self._ubos[name] = (gpu.types.GPUUniformBuf(raw), len(raw))
        else:
            ubo[0].update(raw)
        return self._ubos[name][0]

    def _batches_for(self, key, geo, cache=None):
        """(all-triangles batch, [(material index, batch)]) of a Geometry, built once: kept in
        ``cache`` under ``key`` when given, else under (key, serial) with the meshes' own."""
        import gpu

        cache_key = key if cache is not None else (key, geo.serial)
        cache = self._batches if cache is None else cache
        cached = cache.get(cache_key)
        if cached is not None:
            return cached
        fmt = gpu.types.GPUVertFormat()
        attrs = {"pos": geo.positions, "nor": geo.normals, "uv": geo.uvs, "col": geo.colors, "tan": geo.tangents}
        attrs = {name: data for name, data in attrs.items() if data is not None}
        for name, data in attrs.items():
            fmt.attr_add(id=name, comp_type="F32", len=data.shape[1], fetch_mode="FLOAT")
        vbo = gpu.types.GPUVertBuf(fmt, len(geo.positions))
        for name, data in attrs.items():
            vbo.attr_fill(name, data)
        whole = gpu.types.GPUBatch(type="TRIS", buf=vbo, elem=gpu.types.GPUIndexBuf(type="TRIS", seq=geo.indices))
        parts = []
        for mat_index, first, count in geo.ranges:
            if first == 0 and count == len(geo.indices):
                parts.append((mat_index, whole))
                continue
            ibo = gpu.types.GPUIndexBuf(type="TRIS", seq=geo.indices[first : first + count])
            parts.append((mat_index, gpu.types.GPUBatch(type="TRIS", buf=vbo, elem=ibo)))
        cache[cache_key] = (whole, parts)
        return cache[cache_key]

    def _jitter(self, samples):
        """The jittered-disk texture: (JITTER_SIZE, JITTER_SIZE, samples / 2) RGBA, two 2-D
        offsets per texel, outer ring first (kernels.jitter_disk); a 1x1x1 texture when the
        variant reads no disk (``samples`` 0)."""
        import gpu

        if samples == 0:
            if self._jitter_dummy is None:
                buf = gpu.types.Buffer("FLOAT", 4, [0.0] * 4)
                self._jitter_dummy = gpu.types.GPUTexture((1, 1, 1), format="RGBA32F", data=buf)
            return self._jitter_dummy
        if self._jitter_tex is None or self._jitter_tex[0] != samples:
            disk = kernels.jitter_disk(JITTER_SIZE, samples).astype(np.float32)
            # (y, x, sample, 2) -> 3-D texture (x, y, sample pair) of RGBA: z slowest in memory.
            data = disk.reshape(JITTER_SIZE, JITTER_SIZE, samples // 2, 4).transpose(2, 0, 1, 3)
            buf = gpu.types.Buffer("FLOAT", data.size, data.ravel().tolist())
            tex = gpu.types.GPUTexture((JITTER_SIZE, JITTER_SIZE, samples // 2), format="RGBA32F", data=buf)
            self._jitter_tex = (samples, tex)
        return self._jitter_tex[1]

    def _bins_texture(self, bins):
        """The light-bin masks as an RGBA32F texture (a 1x1 zero texture when not binned)."""
        import gpu

        if bins is None:
            bins = np.zeros((1, 1, 4), np.float32)
        rows, cols = bins.shape[:2]
        buf = gpu.types.Buffer("FLOAT", bins.size, np.ascontiguousarray(bins, np.float32).ravel())
        # Kept until the next frame: the draw that samples it runs after this call returns.
        self._bins_tex = gpu.types.GPUTexture((cols, rows), format="RGBA32F", data=buf)
        return self._bins_tex

    def _shadow_dummy(self):
        import gpu

        if self._dummy_shadow is None:
            self._dummy_shadow = gpu.types.GPUTexture((1, 1), format="R32F")
            self._dummy_shadow.clear(format="FLOAT", value=(1.0,))
        return self._dummy_shadow


def _front_to_back(draws, camera):
    """The draws nearest the camera first (by the nearest point of their bounds), so the
    depth test rejects hidden pixels before they are shaded; flat meshes (grounds, walls)
    after the others: their nearest point is no measure of what they hide, and what stands
    on them is usually in front of them."""
    if len(draws) < 2:
        return draws
    corners = np.stack([d.corners for d in draws])
    lo, hi = corners.min(axis=1), corners.max(axis=1)
    if camera.is_ortho:
        key = np.min(corners @ camera.forward, axis=1)
    else:
        position = camera.position
        key = np.linalg.norm(np.maximum(0.0, np.maximum(lo - position, position - hi)), axis=1)
    key = np.where(np.isfinite(key), key, np.inf)
    return [draws[i] for i in np.lexsort((key, lightspace.flat_boxes(corners)))]


def _fixed_kernel(settings):
    """The radius in texels the scene's shadow filter reads around a lookup (not PCSS, whose
    kernel follows each light's size)."""
    kind = settings.shadow_filter
    if kind == "PCF":
        return (max(int(settings.pcf_kernel_size), 1) // 2) * max(float(settings.pcf_spacing), 0.0) + 1.0
    if kind == "JITTER":
        return max(float(settings.shadow_filter_radius), 0.0) + 1.0
    return 1.0


def _view_corners(camera):
    """The camera frustum's world corners, or None when its matrices are degenerate."""
    from .lightspace import frustum_corners

    try:
        c = frustum_corners(camera.projection @ camera.view)
    except np.linalg.LinAlgError:
        return None
    return c if np.all(np.isfinite(c)) else None


def _gpu_texture_limit():
    import gpu

    return gpu.capabilities.max_texture_size_get()
