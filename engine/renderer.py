"""One frame: shadow passes -> lit pass -> post stack. The same code serves the viewport and
final renders; only where the camera comes from and where the result goes differ.
"""

from dataclasses import dataclass, field

import numpy as np

from . import kernels
from .extract import Material
from .kernels import RING
from .post import PostContext, PostStack
from .programs import (
    FRAME_STRUCT,
    LIGHT_STRUCT,
    LIGHT_TYPES,
    LIT,
    MAX_LIGHTS,
    MAX_PCF_TAPS,
    MAX_DISK_SAMPLES,
    MAX_SHADOW_TILES,
    SHADOW_FILTERS,
    SHADOW_MODES,
    SHADOW_SAMPLER,
    TILE_STRUCT,
    JITTER_SIZE,
    lit_defines,
)
from .shadows import ShadowAtlas, plan_shadows


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
    shadow_samples: int = 16
    shadow_filter_radius: float = 2.0
    shadow_depth_format: str = "FLOAT32"
    shadow_early_out: bool = True
    shadow_sun_fit: str = "VIEW"  # 'VIEW' | 'SCENE'
    specular_model: str = "BLINN"
    film_transparent: bool = False
    frame: int = 1
    layers: list = field(default_factory=list)  # [(effect, enabled, mix, params)]


@dataclass
class FrameStats:
    """What a frame did: read by tests and the benchmark ("model only what a scene requires")."""

    shadow_maps: int = 0  # maps drawn this frame
    shadow_maps_reused: int = 0  # maps whose fit and casters did not change: not redrawn
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
    shadow: object  # GPUTexture, fraction of direct light not blocked (1 for background)
    stats: FrameStats
    width: int
    height: int

    def color_array(self):
        return texture_array(self.color, 4)

    def depth_array(self):
        return texture_array(self.depth, 1)[..., 0]

    def shadow_array(self):
        return texture_array(self.shadow, 1)[..., 0]


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
        self.shadows = ShadowAtlas()
        self._jitter_tex = None
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
        self._shadow = gpu.types.GPUTexture((width, height), format="R32F")
        self._zbuffer = gpu.types.GPUTexture((width, height), format="DEPTH_COMPONENT32F")
        self._fb = gpu.types.GPUFrameBuffer(depth_slot=self._zbuffer, color_slots=(self._color, self._depth, self._shadow))
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

    def _jitter(self, samples):
        """The jittered-disk texture: (JITTER_SIZE, JITTER_SIZE, samples / 2) RGBA, two 2-D
        offsets per texel, outer ring first (kernels.jitter_disk)."""
        import gpu

        if self._jitter_tex is None or self._jitter_tex[0] != samples:
            disk = kernels.jitter_disk(JITTER_SIZE, samples).astype(np.float32)
            # (y, x, sample, 2) -> 3-D texture (x, y, sample pair) of RGBA: z slowest in memory.
            data = disk.reshape(JITTER_SIZE, JITTER_SIZE, samples // 2, 4).transpose(2, 0, 1, 3)
            buf = gpu.types.Buffer("FLOAT", data.size, data.ravel().tolist())
            tex = gpu.types.GPUTexture((JITTER_SIZE, JITTER_SIZE, samples // 2), format="RGBA32F", data=buf)
            self._jitter_tex = (samples, tex)
        return self._jitter_tex[1]

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
        corners = []
        for inst in snapshot.instances:
            geo = snapshot.geometry.get(inst.key)
            if geo is None:
                continue
            whole, parts = self._batches(geo)
            det = float(np.linalg.det(inst.matrix[:3, :3]))
            draws.append((inst, geo, whole, parts, Matrix(inst.matrix.tolist()), det))
            stats.triangles += geo.triangle_count
            box = _box_corners(geo.bounds)
            corners.append(box @ inst.matrix[:3, :3].T + inst.matrix[:3, 3])
        corners = np.stack(corners) if corners else np.zeros((0, 8, 3))

        # Shadow passes: only lights that cast shadows and have casters in reach.
        lights = snapshot.lights[:MAX_LIGHTS]
        map_size = max(1, int(settings.shadow_map_size))
        view_corners = _view_corners(camera) if settings.shadow_sun_fit == "VIEW" else None
        plan = plan_shadows(lights, corners, map_size, view_corners)
        if plan.tiles:
            columns, _rows = self.shadows.grid(len(plan.tiles))
            clamped = _clamp_map_size(map_size, columns)
            if clamped != map_size:
                map_size = clamped
                plan = plan_shadows(lights, corners, map_size, view_corners)
            self.shadows.ensure(map_size, len(plan.tiles), settings.shadow_depth_format)
            shadow_draws = [
                (whole, model, det, (inst.key, inst.matrix.tobytes(), geo.serial))
                for (inst, geo, whole, _p, model, det) in draws
            ]
            self.shadows.render(plan, shadow_draws, self.shaders, settings.shadow_cull_front, stats)
        shadow_tex = self.shadows.texture if plan.tiles else self._shadow_dummy()
        depth_format = self.shadows.depth_format if plan.tiles else "FLOAT32"

        # Frame constants.
        light_rows = []
        for i, light in enumerate(lights):
            half = 0.5 * min(max(light.spot_size, 0.0), np.pi)
            cos_half = float(np.cos(half))
            entry = plan.lights.get(i)
            mode = SHADOW_MODES[entry.mode] if entry else SHADOW_MODES["NONE"]
            tiles = (entry.tiles if entry else []) + [-1] * 6
            radius = light.shadow_radius
            light_rows.append(
                {
                    "color": (*light.color, LIGHT_TYPES[light.type]),
                    "position": (*light.position, light.radius),
                    "direction": (*light.direction, cos_half if light.type == "SPOT" else -2.0),
                    "params": (
                        (1.0 - cos_half) * max(light.spot_blend, 0.0),
                        mode,
                        radius,
                        float(np.tan(0.5 * min(max(light.angle, 0.0), np.pi * 0.99))),
                    ),
                    "tiles": tiles[:4],
                    "tiles2": (tiles[4], tiles[5], light.bias_scale, 0.0),
                }
            )
        tile_rows = [t.record() for t in plan.tiles]
        filt = settings.shadow_filter if settings.shadow_filter in SHADOW_FILTERS else "PCF"
        disk = int(np.clip(settings.shadow_samples // RING * RING, RING, MAX_DISK_SAMPLES))
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
            "shadow_size": (self.shadows.size if plan.tiles else 1, self.shadows.columns, disk, 0.0),
            "filter_params": (settings.shadow_filter_radius, MAX_FILTER_RADIUS, 0.0, 0.0),
        }
        taps = kernels.pcf_kernel(min(settings.pcf_kernel_size, 15)) if filt == "PCF" else np.zeros((1, 3))
        tap_rows = np.zeros((MAX_PCF_TAPS, 4), np.float32)
        tap_rows[: len(taps), :3] = taps
        frame_ubo = self._ubo("frame", pack_struct(FRAME_STRUCT, [frame_row]))
        tile_ubo = self._ubo("tiles", _pad_rows(pack_struct(TILE_STRUCT, tile_rows), MAX_SHADOW_TILES))
        light_ubo = self._ubo("lights", _pad_rows(pack_struct(LIGHT_STRUCT, light_rows), MAX_LIGHTS))
        tap_ubo = self._ubo("taps", tap_rows)

        # Lit pass.
        shader = self.shaders.get(
            LIT, lit_defines(filt, len(taps), settings.specular_model, depth_format, disk, settings.shadow_early_out)
        )
        bg = snapshot.world_color
        alpha = 0.0 if settings.film_transparent else 1.0
        self._color.clear(format="FLOAT", value=(float(bg[0]), float(bg[1]), float(bg[2]), alpha))
        # The second attachment holds view distance; the background is "infinitely" far, as in
        # Blender's own Depth pass.
        self._depth.clear(format="FLOAT", value=(1e10,))
        self._shadow.clear(format="FLOAT", value=(1.0,))
        with self._fb.bind():
            gpu.state.viewport_set(0, 0, width, height)
            self._fb.clear(depth=1.0)
            gpu.state.depth_test_set("LESS_EQUAL")
            gpu.state.depth_mask_set(True)
            shader.bind()
            shader.uniform_block("frame", frame_ubo)
            shader.uniform_block("lights", light_ubo)
            shader.uniform_block("pcf_taps", tap_ubo)
            shader.uniform_block("shadow_tiles", tile_ubo)
            shader.uniform_sampler(SHADOW_SAMPLER, shadow_tex)
            shader.uniform_sampler("jitter_tex", self._jitter(disk))
            for inst, _geo, _whole, parts, model, _det in draws:
                shader.uniform_float("model", model)
                for mat_index, batch in parts:
                    mat = inst.materials[mat_index] if 0 <= mat_index < len(inst.materials) else None
                    mat = mat or DEFAULT_MATERIAL
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

        stats.texture_bytes = width * height * (16 + 4 + 4 + 4) + self.shadows.memory_bytes + ctx.memory_bytes
        stats.shaders_compiled = self.shaders.compiled - compiled_before
        return FrameOutput(color, self._depth, self._shadow, stats, width, height)


DEFAULT_MATERIAL = Material()  # for faces whose material slot is empty
MAX_FILTER_RADIUS = 32.0  # texels: the widest JITTER/PCSS kernel


def _pad_rows(rows, count):
    out = np.zeros((count, rows.shape[1]), np.float32)
    out[: min(len(rows), count)] = rows[:count]
    return out


def _view_corners(camera):
    """The camera frustum's world corners, or None when its matrices are degenerate."""
    from .lightspace import frustum_corners

    try:
        c = frustum_corners(camera.projection @ camera.view)
    except np.linalg.LinAlgError:
        return None
    return c if np.all(np.isfinite(c)) else None


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
