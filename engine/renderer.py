"""One frame: shadow passes -> lit pass -> post stack. The same code serves the viewport and
final renders; only where the camera comes from and where the result goes differ.
"""

from dataclasses import dataclass, field

import numpy as np

from . import kernels
from .post import PostContext, PostStack
from .programs import (
    FRAME_STRUCT,
    LIGHT_STRUCT,
    LIGHT_TYPES,
    LIT,
    MAX_LIGHTS,
    MAX_PCF_TAPS,
    SHADOW_FILTERS,
    SHADOW_SAMPLER,
    TAP_STRUCT,
    lit_defines,
)
from .shadows import ShadowMaps, ShadowView, plan_sun


@dataclass
class RenderSettings:
    """Everything a frame needs from ``scene.penumbra``, as plain values."""

    shadow_filter: str = "PCF"
    shadow_map_size: int = 2048
    pcf_kernel_size: int = 5
    pcf_spacing: float = 1.0
    shadow_bias: float = 0.5
    shadow_slope_bias: float = 1.0
    shadow_normal_offset: float = 1.0
    shadow_cull_front: bool = False
    specular_model: str = "BLINN"
    film_transparent: bool = False
    frame: int = 1
    layers: list = field(default_factory=list)  # [(effect, enabled, mix, params)]


@dataclass
class FrameStats:
    """What a frame did: read by tests and the benchmark ("model only what a scene requires")."""

    shadow_maps: int = 0
    passes: int = 0
    post_passes: int = 0
    draws: int = 0
    triangles: int = 0
    texture_bytes: int = 0
    shaders_compiled: int = 0


@dataclass
class FrameOutput:
    color: object  # GPUTexture, scene-linear RGBA float
    depth: object  # GPUTexture, view-space distance along the camera axis
    stats: FrameStats
    width: int
    height: int

    def color_array(self):
        return texture_array(self.color, 4)

    def depth_array(self):
        return texture_array(self.depth, 1)[..., 0]


def buffer_array(buf):
    """A ``gpu.types.Buffer`` as a C-ordered numpy array of its dimensions.

    Blender 4.5's buffer protocol reports reversed strides, so ``np.asarray`` alone scrambles
    multi-dimensional data there; reading the memory in its own order is right on every line."""
    a = np.asarray(buf)
    return a.ravel(order="K").reshape(tuple(buf.dimensions))


def texture_array(texture, channels):
    """Read a float texture back as an array (height, width, channels), row 0 at the bottom."""
    return buffer_array(texture.read()).astype(np.float32, copy=False).reshape(texture.height, texture.width, channels)


def pack_struct(struct, rows):
    """Pack ``rows`` (list of {field: value}) into a float32 array laid out like std140."""
    out = np.zeros((max(len(rows), 1), struct.floats), np.float32)
    for i, row in enumerate(rows):
        for name, value in row.items():
            off = struct.offset(name)
            v = np.asarray(value, dtype=np.float32)
            if v.shape == (4, 4):
                v = v.T  # GLSL matrices are column-major
            v = v.ravel()
            out[i, off : off + len(v)] = v
    return out


class Renderer:
    """GPU state of one engine instance. Create and use only inside a GPU context."""

    def __init__(self):
        from ..shaders.loader import ShaderCache

        self.shaders = ShaderCache()
        self.shadows = ShadowMaps()
        self.post = PostStack()
        self._size = None
        self._color = self._depth = self._zbuffer = self._fb = None
        self._post_ctx = None
        self._ubos = {}
        self._dummy_shadow = None

    # --- resources ------------------------------------------------------------------------

    def _ensure_targets(self, width, height):
        import gpu

        if self._size == (width, height):
            return
        self._color = gpu.types.GPUTexture((width, height), format="RGBA32F")
        self._depth = gpu.types.GPUTexture((width, height), format="R32F")
        self._zbuffer = gpu.types.GPUTexture((width, height), format="DEPTH_COMPONENT32F")
        self._fb = gpu.types.GPUFrameBuffer(depth_slot=self._zbuffer, color_slots=(self._color, self._depth))
        self._post_ctx = PostContext(self.shaders, width, height)
        self._size = (width, height)

    def _ubo(self, name, data):
        import gpu

        raw = np.ascontiguousarray(data, np.float32).tobytes()
        ubo = self._ubos.get(name)
        if ubo is None or ubo[1] != len(raw):
            self._ubos[name] = (gpu.types.GPUUniformBuf(raw), len(raw))
        else:
            ubo[0].update(raw)
        return self._ubos[name][0]

    def _batches(self, geo):
        """(all-triangles batch, [(material index, batch)]) for a Geometry, built once."""
        import gpu

        cached = geo.gpu.get("batches")
        if cached is not None:
            return cached
        fmt = gpu.types.GPUVertFormat()
        fmt.attr_add(id="pos", comp_type="F32", len=3, fetch_mode="FLOAT")
        fmt.attr_add(id="nor", comp_type="F32", len=3, fetch_mode="FLOAT")
        vbo = gpu.types.GPUVertBuf(fmt, len(geo.positions))
        vbo.attr_fill("pos", geo.positions)
        vbo.attr_fill("nor", geo.normals)
        whole = gpu.types.GPUBatch(type="TRIS", buf=vbo)
        parts = []
        for mat_index, first, count in geo.ranges:
            if first == 0 and count == len(geo.positions):
                parts.append((mat_index, whole))
                continue
            ibo = gpu.types.GPUIndexBuf(type="TRIS", seq=np.arange(first, first + count, dtype=np.int32).reshape(-1, 3))
            parts.append((mat_index, gpu.types.GPUBatch(type="TRIS", buf=vbo, elem=ibo)))
        geo.gpu["batches"] = (whole, parts)
        return geo.gpu["batches"]

    def _shadow_dummy(self):
        import gpu

        if self._dummy_shadow is None:
            self._dummy_shadow = gpu.types.GPUTexture((1, 1), format="R32F")
            self._dummy_shadow.clear(format="FLOAT", value=(1.0,))
        return self._dummy_shadow

    # --- frame ----------------------------------------------------------------------------

    def render(self, snapshot, camera, settings, width, height):
        import gpu
        from mathutils import Matrix

        stats = FrameStats()
        compiled_before = self.shaders.compiled
        self._ensure_targets(width, height)

        draws = []  # (instance, geometry, whole batch, parts, model Matrix, det)
        world_points = []
        for inst in snapshot.instances:
            geo = snapshot.geometry.get(inst.key)
            if geo is None:
                continue
            whole, parts = self._batches(geo)
            det = float(np.linalg.det(inst.matrix[:3, :3]))
            draws.append((inst, geo, whole, parts, Matrix(inst.matrix.tolist()), det))
            stats.triangles += geo.triangle_count
            corners = _box_corners(geo.bounds)
            world_points.append(corners @ inst.matrix[:3, :3].T + inst.matrix[:3, 3])
        world_points = np.concatenate(world_points) if world_points else np.zeros((0, 3))

        # Shadow passes: only lights that cast shadows and have casters in reach. Planning
        # uses the requested size; the atlas may clamp it to fit the GPU's texture limit.
        map_size = max(1, int(settings.shadow_map_size))
        lights = snapshot.lights[:MAX_LIGHTS]
        shadow_views = {}
        plans = []
        for i, light in enumerate(lights):
            if not light.use_shadow or light.type != "SUN" or len(world_points) == 0:
                continue
            plan = plan_sun(light, world_points, map_size)
            if plan is not None:
                plans.append((i, plan))
        if plans:
            columns, _rows = self.shadows.grid(len(plans))
            map_size = _clamp_map_size(settings.shadow_map_size, columns)
            self.shadows.ensure(map_size, len(plans))
            self.shadows.clear()
            shadow_draws = [(whole, model, det) for (_i, _g, whole, _p, model, det) in draws]
            for tile, (i, (view, proj, texel, depth_per_world)) in enumerate(plans):
                vp = proj @ view
                self.shadows.render_tile(tile, vp, shadow_draws, self.shaders, settings.shadow_cull_front, stats)
                shadow_views[i] = ShadowView(tile, vp, texel, depth_per_world)
        shadow_tex = self.shadows.texture if plans else self._shadow_dummy()

        # Frame constants.
        light_rows = []
        for i, light in enumerate(lights):
            half = 0.5 * min(max(light.spot_size, 0.0), np.pi)
            cos_half = float(np.cos(half))
            sv = shadow_views.get(i)
            light_rows.append(
                {
                    "color": (*light.color, LIGHT_TYPES[light.type]),
                    "position": (*light.position, light.radius),
                    "direction": (*light.direction, cos_half if light.type == "SPOT" else -2.0),
                    "params": (
                        (1.0 - cos_half) * max(light.spot_blend, 0.0),
                        sv.tile if sv else -1.0,
                        sv.texel_world if sv else 0.0,
                        sv.depth_per_world if sv else 0.0,
                    ),
                    "shadow_matrix": sv.matrix if sv else np.eye(4),
                }
            )
        view_proj = camera.projection @ camera.view
        frame_row = {
            "view_proj": view_proj,
            "view": camera.view,
            "camera_position": (*camera.position, 1.0 if camera.is_ortho else 0.0),
            "camera_forward": (*camera.forward, 0.0),
            "world_color": (*snapshot.world_color, 0.0),
            "counts": (len(lights), 0.0, 0.0, 0.0),
            "shadow_params": (
                settings.shadow_bias,
                settings.shadow_slope_bias,
                settings.shadow_normal_offset,
                settings.pcf_spacing,
            ),
            "shadow_size": (self.shadows.size if plans else 1, self.shadows.columns, 0.0, 0.0),
        }
        filt = settings.shadow_filter if settings.shadow_filter in SHADOW_FILTERS else "PCF"
        taps = kernels.pcf_kernel(min(settings.pcf_kernel_size, 15)) if filt == "PCF" else np.zeros((1, 3))
        tap_rows = np.zeros((MAX_PCF_TAPS, 4), np.float32)
        tap_rows[: len(taps), :3] = taps
        frame_ubo = self._ubo("frame", pack_struct(FRAME_STRUCT, [frame_row]))
        light_ubo = self._ubo("lights", _pad_rows(pack_struct(LIGHT_STRUCT, light_rows), MAX_LIGHTS))
        tap_ubo = self._ubo("taps", tap_rows)

        # Lit pass.
        shader = self.shaders.get(LIT, lit_defines(filt, len(taps), settings.specular_model))
        bg = snapshot.world_color
        alpha = 0.0 if settings.film_transparent else 1.0
        self._color.clear(format="FLOAT", value=(float(bg[0]), float(bg[1]), float(bg[2]), alpha))
        # The second attachment holds view distance; the background is "infinitely" far, as in
        # Blender's own Depth pass.
        self._depth.clear(format="FLOAT", value=(1e10,))
        with self._fb.bind():
            gpu.state.viewport_set(0, 0, width, height)
            self._fb.clear(depth=1.0)
            gpu.state.depth_test_set("LESS_EQUAL")
            gpu.state.depth_mask_set(True)
            shader.bind()
            shader.uniform_block("frame", frame_ubo)
            shader.uniform_block("lights", light_ubo)
            shader.uniform_block("pcf_taps", tap_ubo)
            shader.uniform_sampler(SHADOW_SAMPLER, shadow_tex)
            for inst, _geo, _whole, parts, model, _det in draws:
                shader.uniform_float("model", model)
                for mat_index, batch in parts:
                    mat = inst.materials[mat_index] if 0 <= mat_index < len(inst.materials) else None
                    if mat is None:
                        from .extract import Material

                        mat = Material()
                    shader.uniform_float("base_color", tuple(mat.base_color))
                    shader.uniform_float("material", (mat.roughness, mat.specular, mat.metallic, 0.0))
                    batch.draw(shader)
                    stats.draws += 1
            gpu.state.depth_test_set("NONE")
            gpu.state.depth_mask_set(False)
        stats.passes += 1

        # Post stack.
        ctx = self._post_ctx
        ctx.frame = settings.frame
        ctx.stats = stats
        color = self.post.run(ctx, self._color, settings.layers)

        stats.texture_bytes = width * height * (16 + 4 + 4) + self.shadows.memory_bytes + ctx.memory_bytes
        stats.shaders_compiled = self.shaders.compiled - compiled_before
        return FrameOutput(color, self._depth, stats, width, height)


def _pad_rows(rows, count):
    out = np.zeros((count, rows.shape[1]), np.float32)
    out[: min(len(rows), count)] = rows[:count]
    return out


def _box_corners(bounds):
    from .lightspace import box_corners

    return box_corners(bounds[0], bounds[1])


def _clamp_map_size(size, columns=1):
    import sys

    import gpu

    limit = gpu.capabilities.max_texture_size_get() // max(1, columns)
    clamped = int(min(max(int(size), 1), limit))
    if clamped != int(size):
        print(f"Penumbra: shadow map size {size} clamped to {clamped} (GPU limit)", file=sys.stderr)
    return clamped
