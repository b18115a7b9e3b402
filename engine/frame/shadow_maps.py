"""The depth pass: the shadow atlas of one engine instance and what each instance draws into
it (``Caster``). Which maps a frame needs, and how each is fitted, is decided beforehand
without a GPU (``shadows.planning.plan_shadows``)."""

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from ...shaders.loader import set_uniforms
from ..enums import DEPTH_FORMAT
from ..gpu_pool import UniformBlocks, new_texture
from ..shadows.planning import pack_tiles
from .film_programs import SCALED_COPY
from .programs import RSM_FORMAT, RSM_TEXEL_BYTES, TILE_STRUCT, depth_defines, packed_tiles
from .shadow_programs import (
    INSTANCE_TABLE_ROWS,
    instanced_shadow_program,
    shadow_cutout_program,
    shadow_hair_program,
    shadow_program,
    shadow_tree_program,
)


@dataclass
class TreeCutout:
    """A caster part whose alpha a compiled node tree gives (``shadow_programs.shadow_tree_program``):
    the tree, its node_constants block, its images' textures and per-draw push constants."""

    tree: object
    constants: object
    images: tuple
    uniforms: dict


@dataclass
class Caster:
    """One instance as it draws into shadow maps."""

    batches: list  # GPUBatches drawn whole (opaque material parts)
    model: object  # mathutils.Matrix
    det: float  # sign of the model matrix (winding under negative scale)
    identity: tuple  # what a tile's content depends on
    # (batch, material UBO, (alpha texture, its image_premultiplied bits) or None, TreeCutout or
    # None): covers a texel in a
    # fraction alpha of the samples
    cutouts: list = field(default_factory=list)
    cull_back: bool = False  # every material asks for shadow back-face culling: faces away from the light cast nothing
    closed: bool = False  # a closed opaque surface (renderer.CULL_CLOSED): its back faces are hidden from outside
    corners: object = None  # (8, 3) world corners of its bounds, with ``closed``
    triangles: int = 0  # triangles of ``batches`` (drawn whole)
    level: int = None  # drawn into this map at a level of detail (``_at_level``), else None
    hair: str = None  # hair strips (Render > Curves > Shape: STRAND or STRIP), drawn by ``shadow_hair_program``
    # Reflective shadow maps (``ShadowAtlas.render`` with ``rsm``): ``batches`` drawn per material
    # part, (batch, material UBO) each, and what their albedo depends on (the tile's key).
    rsm_parts: list = None
    rsm_key: tuple = ()


def draw_cutout(program, part, tile_ubo, alpha_offset, model, origin=None):
    """Draw one alpha cut-out ``part`` (of ``Caster.cutouts``: its batch, material block, (alpha
    texture, premultiplied bits) or None, ``TreeCutout`` or None) with ``program`` (the
    cut-out or node-tree depth program of the map, or of the camera depth prepass) into the
    tile of ``tile_ubo`` at this sample's ``alpha_offset``. ``origin``: the frame origin a
    compiled tree's ORIGIN reads."""
    batch, material_ubo, texture, tree = part
    program.bind()
    if tree is not None:
        program.uniform_block("node_constants", tree.constants)
        for i, image in enumerate(tree.images):
            program.uniform_sampler(f"node_image_{i}", image)
        uniforms = dict(tree.uniforms)
        if "ORIGIN" in tree.tree.needs:
            o = origin if origin is not None else (0.0, 0.0, 0.0)
            uniforms["node_origin"] = tuple(float(x) for x in o)
        set_uniforms(program, uniforms)
    program.uniform_block("tile", tile_ubo)
    program.uniform_float("alpha_offset", alpha_offset)
    program.uniform_float("model", model)
    program.uniform_block("material", material_ubo)
    if texture is not None:
        program.uniform_sampler("tex_alpha", texture[0])
        set_uniforms(program, {"image_premultiplied": texture[1]})
    batch.draw(program)


def _crosses_near(fit, casters):
    """Whether a caster's bounds cross the near plane of ``fit`` (some corners nearer the light
    than it, some beyond)."""
    boxes = [c.corners for c in casters if getattr(c, "corners", None) is not None]
    if not boxes:
        return False
    m = fit.view_proj
    points = np.stack(boxes)  # (n, 8, 3)
    z = points @ m[2, :3] + m[2, 3]
    w = points @ m[3, :3] + m[3, 3]
    nearer = z < -w
    return bool(np.any(nearer.any(axis=1) & ~nearer.all(axis=1)))


def _at_level(caster, batches, level, triangles):
    """``caster`` as drawn into one map at a level of detail: its content key names the level,
    and back faces are not culled (a merged surface is not tested for closedness)."""
    return dataclasses.replace(
        caster,
        batches=batches,
        identity=(*caster.identity, "level", level),
        closed=False,
        triangles=triangles,
        level=level,
    )


class ShadowAtlas:
    """The atlas of one engine instance: square slots in a grid ``columns`` wide, as wide as
    the frame's widest map; narrower maps share a slot (``pack_tiles``). Tiles remember what
    they hold so unchanged maps are reused.

    Memory is the slots the packed maps take (maps of power-of-two sizes leave no gaps in a
    slot) and one slot more at most: a FLOAT32 atlas is a depth texture the depth pass writes
    directly (4 bytes a texel, nothing else); FLOAT16 and RGBA8 maps are drawn in one
    slot-sized scratch target (colour and depth) and copied into a colour atlas of their own
    format (2 or 4 bytes a texel).

    With ``rsm`` (Light Paths > Diffuse Bounces 1) the atlas is also a set of reflective
    shadow maps (Dachsbacher and Stamminger 2005): two RGBA16F targets of its size hold per
    texel the diffuse albedo and the light-facing world normal of the surface the map sees
    there (``shadow_programs.with_rsm_output``), 16 bytes a texel more, drawn in the same pass as the
    depth (a FLOAT32 atlas's framebuffer gets them as colour attachments; other formats draw
    them in the scratch target and copy them like the depth). Without it nothing changes."""

    def __init__(self, pool=None):
        self.size = 0
        self.count = 0
        self.columns = 1
        self.depth_format = "FLOAT32"
        self.rsm = False  # the atlas has the reflective targets
        self.rsm_refused = ""  # why the GPU refused them in the last ``ensure`` ("": it did not)
        self.flux = None  # (rsm) albedo of the surface each texel sees, RGBA16F
        self.normal = None  # (rsm) its world normal, turned towards the light, RGBA16F
        self._rsm_framebuffers = ()  # (rsm, not FLOAT32) the targets the scratch is copied into
        self._pool = pool  # a gpu_pool.TexturePool the atlas texture comes from and goes back to
        self.texture = None
        self._framebuffer = None
        self._scratch = None  # (colour, depth, framebuffer) of one tile, non-FLOAT32 formats
        self._copy_batch = None
        self._ubos = []
        self._instanced = UniformBlocks()  # the instanced pass's blocks: the tiles, the instance table
        self._tiles_bytes = None  # what its tiles block holds
        self._contents = {}  # tile index -> what its map holds
        # Inside a frame the atlas only grows (``ShadowPass.draw_batch``): a batch with fewer
        # maps than the last, or the settling pilot's, keeps the larger atlas, not a new one.
        self.growing = False
        self.uploaded = 0  # bytes of tile blocks sent to the GPU since creation

    @staticmethod
    def grid(count):
        columns = max(1, math.ceil(math.sqrt(count)))
        rows = max(1, math.ceil(count / columns))
        return columns, rows

    def ensure(self, size, count, depth_format, rsm=False):
        """Make the atlas hold ``count`` maps of ``size`` texels stored as ``depth_format``,
        with the reflective targets when ``rsm``. Where the GPU refuses the reflective targets
        (an allocation that fails), the atlas is made without them and ``rsm_refused`` says
        why: the frame renders without the bounce rather than failing."""
        self.rsm_refused = ""
        try:
            self._allocate(size, count, depth_format, rsm)
        except Exception as exc:  # gpu.types.GPUTexture raises when the driver refuses
            self.free()
            if not rsm:
                raise
            self._allocate(size, count, depth_format, False)
            self.rsm_refused = str(exc) or type(exc).__name__

    def _allocate(self, size, count, depth_format, rsm):
        import gpu

        count = max(1, count)
        columns, rows = self.grid(count)
        rsm = bool(rsm)
        if (
            self.texture is not None
            and (self.size, self.depth_format, self.rsm) == (size, depth_format, rsm)
            and self.count >= count
            and (self.columns == columns or self.growing)
        ):
            return  # (while ``growing`` a larger grid holds the maps too: ``place`` uses its columns)
        self.free()
        self.size, self.count, self.columns, self.depth_format = size, columns * rows, columns, depth_format
        self.rsm = rsm
        dims = (columns * size, rows * size)
        fmt = DEPTH_FORMAT[depth_format]
        # Read with texelFetch only, so the sampler's filter mode never matters. A pooled
        # texture holds another render's maps: every map is drawn before it is read.
        self.texture = new_texture(self._pool, dims, fmt.texture)
        extra = ()
        if rsm:
            self.flux = new_texture(self._pool, dims, RSM_FORMAT)
            self.normal = new_texture(self._pool, dims, RSM_FORMAT)
            extra = (self.flux, self.normal)
        if fmt.depth_only:
            if extra:
                self._framebuffer = gpu.types.GPUFrameBuffer(depth_slot=self.texture, color_slots=extra)
            else:
                self._framebuffer = gpu.types.GPUFrameBuffer(depth_slot=self.texture)
        else:
            self._framebuffer = gpu.types.GPUFrameBuffer(color_slots=(self.texture,))
            color = gpu.types.GPUTexture((size, size), format=fmt.texture)
            depth = gpu.types.GPUTexture((size, size), format="DEPTH_COMPONENT32F")
            scratch = [color]
            if rsm:
                scratch += [gpu.types.GPUTexture((size, size), format=RSM_FORMAT) for _ in range(2)]
                self._rsm_framebuffers = tuple(gpu.types.GPUFrameBuffer(color_slots=(t,)) for t in extra)
            self._scratch = (
                color,
                depth,
                gpu.types.GPUFrameBuffer(depth_slot=depth, color_slots=tuple(scratch)),
                tuple(scratch[1:]),
            )
        self._contents = {}

    @property
    def memory_bytes(self):
        if self.texture is None:
            return 0
        texel = DEPTH_FORMAT[self.depth_format].bytes + (RSM_TEXEL_BYTES if self.rsm else 0)
        scratch = 0 if self._scratch is None else self.size * self.size * (texel + 4)
        return self.texture.width * self.texture.height * texel + scratch

    def free(self):
        """Drop the GPU objects (inside a GPU context); the atlas texture goes to the pool."""
        self._framebuffer = None
        self._scratch = None
        self._rsm_framebuffers = ()
        self._copy_batch = None
        if self._pool is not None:
            self._pool.give([t for t in (self.texture, self.flux, self.normal) if t is not None])
        self.texture = self.flux = self.normal = None
        self.rsm = False
        self._ubos = []
        self._instanced = UniformBlocks()
        self._tiles_bytes = None
        self._contents = {}
        self.size = self.count = 0
        self.columns = 1

    def place(self, plan, depth_format, rsm=False):
        """Pack the plan's maps (``pack_tiles``), make the atlas hold them and set each tile's
        ``origin``; ``rsm``: with the reflective targets."""
        slot, count, where = pack_tiles([t.size for t in plan.tiles])
        self.ensure(slot, count, depth_format, rsm)
        for tile, (index, x, y) in zip(plan.tiles, where, strict=True):
            tile.origin = ((index % self.columns) * self.size + x, (index // self.columns) * self.size + y)

    def _tile_ubo(self, index, data):
        import gpu

        raw = data.tobytes()
        self.uploaded += len(raw)
        while len(self._ubos) <= index:
            self._ubos.append(gpu.types.GPUUniformBuf(raw))
        self._ubos[index].update(raw)
        return self._ubos[index]

    def _program(self, shaders, raster, instanced=False):
        """The map's depth program; ``raster``: an orthographic tile of a depth-buffer map."""
        defines = depth_defines(self.depth_format)
        if instanced:
            return shaders.get(instanced_shadow_program(self.depth_format, raster), defines)
        return shaders.get(shadow_program(self.depth_format, raster, rsm=self.rsm), defines)

    def _cutout_program(self, shaders, textured, raster):
        """The map's alpha cut-out program, compiled only when a caster has alpha."""
        program = shadow_cutout_program(self.depth_format, textured, raster, rsm=self.rsm)
        return shaders.get(program, depth_defines(self.depth_format))

    def render(self, plan, draws, shaders, cull_front, stats, alpha_offset=0.5, origin=None, levels=None):
        """Draw every tile of ``plan`` whose content changed. ``draws``: per instance a
        ``Caster``, or None for an instance that casts no shadow; a tile's key is its fit and
        its casters. ``origin``: the frame origin the casters' model matrices are relative to.
        ``levels``: {(tile index, instance index): (batches, level, triangles)}, casters drawn
        into that tile at a level of detail (``shadow_pass.map_levels``) instead of whole.
        ``alpha_offset``: the sample's alpha-hash offset, or one per tile (the maps of a batch
        of samples, ``ShadowPass.draw_batch``): alpha cut-outs cover other texels in each."""
        alphas = list(alpha_offset) if isinstance(alpha_offset, (list, tuple)) else [alpha_offset] * len(plan.tiles)
        work = self._changed(plan, draws, cull_front, stats, alphas, levels or {})
        depth_only = DEPTH_FORMAT[self.depth_format].depth_only
        # Every map redrawn (a final render's frame) and filling most of the atlas: one clear of
        # the whole atlas, not one scissored clear per map (which GL may draw as a quad).
        used = sum(t.size**2 for _i, t, _c, _k in work)
        cleared = depth_only and len(work) == len(plan.tiles) and 2 * used >= self.count * self.size**2
        if cleared:
            with self._framebuffer.bind():
                if self.rsm:
                    self._framebuffer.clear(color=(0.0, 0.0, 0.0, 0.0), depth=1.0)
                else:
                    self._framebuffer.clear(depth=1.0)
        if depth_only and not self.rsm:
            self._render_depth_maps(plan, work, shaders, cull_front, stats, (alphas, origin), cleared)
            return
        for index, tile, casters, key in work:
            self._render_tile(index, tile, casters, shaders, cull_front, stats, (alphas[index], origin), cleared)
            self._drawn(index, key, tile, casters, stats)

    def _changed(self, plan, draws, cull_front, stats, alphas, levels):
        """[(tile index, tile, its casters, its content key)] of the tiles of ``plan`` whose
        content is not already in the atlas (those that are count as reused)."""
        work = []
        for index, tile in enumerate(plan.tiles):
            casters = []
            for c in tile.casters:
                if draws[c] is not None:
                    lod = levels.get((index, c))
                    casters.append(draws[c] if lod is None else _at_level(draws[c], *lod))
            key = (
                tile.fit.view_proj.tobytes(),
                tile.fit.near,
                tile.fit.far,
                tile.size,
                tile.origin,
                cull_front,
                tuple((c.identity, c.cull_back) for c in casters),
                # The reflective targets hold the casters' albedo as well.
                tuple(c.rsm_key for c in casters) if self.rsm else None,
                # Alpha casters cover other texels in each sample: such a map is redrawn per sample.
                alphas[index] if any(c.cutouts for c in casters) else None,
            )
            if self._contents.get(index) == key:
                stats.shadow_maps_reused += 1
                continue
            work.append((index, tile, casters, key))
        return work

    def _drawn(self, index, key, tile, casters, stats):
        """Tile ``index`` now holds ``key``: remembered, and counted."""
        self._contents[index] = key
        stats.shadow_simplified += sum(1 for c in casters if c.level is not None)
        stats.passes += 1
        stats.shadow_maps += 1
        stats.shadow_texels += tile.size * tile.size

    def _render_depth_maps(self, plan, work, shaders, cull_front, stats, sample, cleared):
        """Depth-buffer maps (FLOAT32, no reflective targets): each opaque caster batch is drawn
        once for all the maps of the sample it is in (instanced); alpha cut-outs and hair strips
        tile by tile. ``sample``: (alpha offset per tile, frame origin); ``cleared``: the whole
        atlas was."""
        import gpu

        if not cleared and work:
            with self._framebuffer.bind():
                gpu.state.scissor_test_set(True)
                for _index, tile, _casters, _key in work:
                    gpu.state.viewport_set(*tile.origin, tile.size, tile.size)
                    gpu.state.scissor_set(*tile.origin, tile.size, tile.size)
                    self._framebuffer.clear(depth=1.0)
                gpu.state.scissor_test_set(False)
        alphas, origin = sample
        self._render_instanced(plan, work, shaders, cull_front, stats, origin)
        for index, tile, casters, key in work:
            if any(c.cutouts or c.hair is not None for c in casters):
                (x0, y0), n = tile.origin, tile.size
                with self._framebuffer.bind():
                    gpu.state.viewport_set(x0, y0, n, n)
                    gpu.state.depth_test_set("LESS")
                    gpu.state.depth_mask_set(True)
                    tile_ubo = self._tile_ubo(index, TILE_STRUCT.pack([tile.record(origin)]))
                    raster = tile.fit.orthographic and not _crosses_near(tile.fit, casters)
                    self._draw_strips_and_cutouts(casters, tile_ubo, raster, shaders, (alphas[index], origin), stats)
                    gpu.state.depth_test_set("NONE")
                    gpu.state.depth_mask_set(False)
            self._drawn(index, key, tile, casters, stats)

    def _render_tile(self, index, tile, casters, shaders, cull_front, stats, sample, cleared):
        """Map ``index`` drawn on its own: into its place in a depth atlas (with reflective
        targets), or into the scratch target and copied into the colour atlas (FLOAT16, RGBA8).
        ``sample``: (alpha offset, frame origin); ``cleared``: the whole atlas was."""
        import gpu

        depth_only = DEPTH_FORMAT[self.depth_format].depth_only
        (x0, y0), n = tile.origin, tile.size
        target = self._framebuffer if depth_only else self._scratch[2]
        with target.bind():
            if depth_only:
                gpu.state.viewport_set(x0, y0, n, n)
                if not cleared:
                    gpu.state.scissor_set(x0, y0, n, n)
                    gpu.state.scissor_test_set(True)
                    if self.rsm:
                        target.clear(color=(0.0, 0.0, 0.0, 0.0), depth=1.0)
                    else:
                        target.clear(depth=1.0)
                    gpu.state.scissor_test_set(False)
            else:
                gpu.state.viewport_set(0, 0, n, n)
                target.clear(color=(1.0, 1.0, 1.0, 1.0), depth=1.0)
            gpu.state.depth_test_set("LESS")
            gpu.state.depth_mask_set(True)
            tile_ubo = self._tile_ubo(index, TILE_STRUCT.pack([tile.record(sample[1])]))
            # The depth pass flattens casters nearer the light than the near plane per
            # vertex (pancaking), exact only for triangles wholly nearer: a caster that
            # crosses the plane (a ground under light from below it) would have its depth
            # bent, so such a tile writes each fragment's own depth, clamped, instead of the
            # rasterised one.
            raster = depth_only and tile.fit.orthographic and not _crosses_near(tile.fit, casters)
            shader = self._program(shaders, raster)
            shader.bind()
            shader.uniform_block("tile", tile_ubo)
            self._draw_casters(shader, tile, casters, cull_front, stats)
            self._draw_strips_and_cutouts(casters, tile_ubo, raster, shaders, sample, stats)
            gpu.state.face_culling_set("NONE")
            gpu.state.front_facing_set(False)
            gpu.state.depth_test_set("NONE")
            gpu.state.depth_mask_set(False)
        if not depth_only:
            self._copy_scratch(x0, y0, n, shaders)
            for src, fb in zip(self._scratch[3], self._rsm_framebuffers, strict=True):
                self._copy_scratch(x0, y0, n, shaders, src, fb)
            stats.passes += 1

    def _draw_casters(self, shader, tile, casters, cull_front, stats):
        """A tile's opaque casters with ``shader`` bound: whole, or per material part into the
        reflective targets (its albedo); hair strips are drawn apart."""
        import gpu

        # Closed casters wholly in front of the light (w > 0 at every corner: no
        # clipping, and the light outside them) cast with their faces toward the light.
        front = set()
        closed = [c for c in casters if c.closed] if not cull_front else []
        if closed:
            w_row = tile.fit.view_proj[3]
            ok = np.all(np.stack([c.corners for c in closed]) @ w_row[:3] + w_row[3] > 0.0, axis=1)
            front = {id(c) for c, inside in zip(closed, ok, strict=True) if inside}
            stats.closed_culled += len(front)
        for caster in casters:
            if caster.hair is not None:
                continue  # with the strips' program
            if cull_front or caster.cull_back or id(caster) in front:
                gpu.state.face_culling_set("FRONT" if cull_front else "BACK")
                gpu.state.front_facing_set(caster.det < 0.0)
            else:
                gpu.state.face_culling_set("NONE")
            shader.uniform_float("model", caster.model)
            if self.rsm and caster.rsm_parts is not None:  # per material: its albedo
                for batch, material_ubo in caster.rsm_parts:
                    shader.uniform_block("material", material_ubo)
                    batch.draw(shader)
                    stats.draws += 1
                    stats.shadow_draws += 1
                stats.shadow_triangles += caster.triangles
                continue
            for batch in caster.batches:
                batch.draw(shader)
                stats.draws += 1
                stats.shadow_draws += 1
            stats.shadow_triangles += caster.triangles

    def _render_instanced(self, plan, work, shaders, cull_front, stats, origin):
        """The opaque casters of the maps in ``work`` into the depth atlas, instanced: one draw
        per caster batch and group of its maps that share a program (orthographic tiles take
        the rasterised depth) and face culling, whatever the number of maps. The tiles go in
        one uniform block, the (caster, map) pairs in an instance table read by instance."""
        import gpu

        groups = {}  # (raster, culling, model, batches) -> (caster, [tile indices])
        for index, tile, casters, _key in work:
            raster = tile.fit.orthographic and not _crosses_near(tile.fit, casters)
            front = self._facing_light(tile, casters, cull_front, stats)
            for caster in casters:
                if caster.hair is not None or not caster.batches:
                    continue
                if cull_front or caster.cull_back or id(caster) in front:
                    culling = ("FRONT" if cull_front else "BACK", caster.det < 0.0)
                else:
                    culling = ("NONE", False)
                key = (raster, culling, id(caster.model), tuple(id(b) for b in caster.batches))
                groups.setdefault(key, (caster, []))[1].append(index)
        if not groups:
            return
        tiles = packed_tiles(plan, origin)
        tiles_ubo = self._instance_ubo("tiles", tiles)
        order = sorted(groups.items(), key=lambda item: (not item[0][0], item[0][1]))
        capacity = 4 * INSTANCE_TABLE_ROWS
        chunks, chunk, used = [], [], 0
        for key, (caster, indices) in order:
            for start in range(0, len(indices), capacity):
                part = indices[start : start + capacity]
                if used + len(part) > capacity:
                    chunks.append(chunk)
                    chunk, used = [], 0
                chunk.append((key[0], key[1], caster, part, used))
                used += len(part)
        chunks.append(chunk)
        width, height = self.texture.width, self.texture.height
        with self._framebuffer.bind():
            gpu.state.viewport_set(0, 0, width, height)
            gpu.state.depth_test_set("LESS")
            gpu.state.depth_mask_set(True)
            gpu.state.clip_distances_set(4)
            for chunk in chunks:
                table = np.zeros(4 * INSTANCE_TABLE_ROWS, np.int32)
                flat = [i for *_head, part, _base in chunk for i in part]
                table[: len(flat)] = flat
                table_ubo = self._instance_ubo("table", table)
                bound, culling_now = None, None
                for raster, culling, caster, part, base in chunk:
                    if bound is not raster:
                        shader = self._program(shaders, raster, instanced=True)
                        shader.bind()
                        shader.uniform_block("tiles", tiles_ubo)
                        shader.uniform_block("instance_tiles", table_ubo)
                        shader.uniform_float("atlas_size", (float(width), float(height)))
                        bound = raster
                    if culling != culling_now:
                        gpu.state.face_culling_set(culling[0])
                        gpu.state.front_facing_set(culling[1])
                        culling_now = culling
                    shader.uniform_float("model", caster.model)
                    shader.uniform_int("instance_base", base)
                    for batch in caster.batches:
                        batch.draw_instanced(shader, instance_start=0, instance_count=len(part))
                        stats.draws += 1
                        stats.shadow_draws += 1
                    stats.shadow_triangles += caster.triangles * len(part)
            gpu.state.clip_distances_set(0)
            gpu.state.face_culling_set("NONE")
            gpu.state.front_facing_set(False)
            gpu.state.depth_test_set("NONE")
            gpu.state.depth_mask_set(False)

    @staticmethod
    def _facing_light(tile, casters, cull_front, stats):
        """The closed casters wholly in front of the tile's light (w > 0 at every corner: no
        clipping, and the light outside them): they cast with their faces toward the light."""
        closed = [c for c in casters if c.closed] if not cull_front else []
        if not closed:
            return set()
        w_row = tile.fit.view_proj[3]
        ok = np.all(np.stack([c.corners for c in closed]) @ w_row[:3] + w_row[3] > 0.0, axis=1)
        stats.closed_culled += int(np.count_nonzero(ok))
        return {id(c) for c, inside in zip(closed, ok, strict=True) if inside}

    def tiles_block(self, packed):
        """The instanced pass's block of the sample's tiles when it holds ``packed`` (the lit
        pass's ``FrameData.tiles``: the same records), so the lit pass binds it rather than
        uploading the same bytes again; else None."""
        block = self._instanced.peek("tiles")
        if block is None or self._tiles_bytes != np.ascontiguousarray(packed).tobytes():
            return None
        return block

    def _instance_ubo(self, name, data):
        """The instanced pass's uniform block ``name`` (the tiles, the instance table) holding
        ``data``, made on first use and updated after."""
        raw = np.ascontiguousarray(data).tobytes()
        if name == "tiles":
            if raw == self._tiles_bytes and self._instanced.peek(name) is not None:
                return self._instanced.peek(name)
            self._tiles_bytes = raw
        self.uploaded += len(raw)
        return self._instanced.get(name, raw)

    def _draw_strips_and_cutouts(self, casters, tile_ubo, raster, shaders, sample, stats):
        """A tile's hair strips and alpha cut-outs (both sides cast), with the tile's block bound.
        ``sample``: (alpha offset, frame origin)."""
        import gpu

        gpu.state.face_culling_set("NONE")  # alpha surfaces are often single planes: both sides cast
        strips = [c for c in casters if c.hair is not None]
        if strips:
            hair = shaders.get(
                shadow_hair_program(self.depth_format, raster, rsm=self.rsm), depth_defines(self.depth_format)
            )
            hair.bind()
            hair.uniform_block("tile", tile_ubo)
            for caster in strips:
                hair.uniform_float("model", caster.model)
                hair.uniform_float("hair_texels", 1.0 if caster.hair == "STRAND" else 0.0)
                for batch in caster.batches:
                    batch.draw(hair)
                    stats.draws += 1
                    stats.shadow_draws += 1
                stats.shadow_triangles += caster.triangles
        alpha_offset, origin = sample
        for caster in casters:
            for part in caster.cutouts:
                _batch, _material_ubo, texture, tree = part
                if tree is not None:
                    program = shadow_tree_program(self.depth_format, tree.tree, raster, rsm=self.rsm)
                    cut = shaders.get(program, depth_defines(self.depth_format))
                else:
                    cut = self._cutout_program(shaders, texture is not None, raster)
                draw_cutout(cut, part, tile_ubo, alpha_offset, caster.model, origin)
                stats.draws += 1
                stats.shadow_draws += 1

    def _copy_scratch(self, x0, y0, n, shaders, src=None, framebuffer=None):
        import gpu
        from gpu_extras.batch import batch_for_shader

        shader = shaders.get(SCALED_COPY)
        if self._copy_batch is None:
            self._copy_batch = batch_for_shader(shader, "TRIS", {"pos": ((-1, -1), (3, -1), (-1, 3))})
        framebuffer = self._framebuffer if framebuffer is None else framebuffer
        with framebuffer.bind():
            gpu.state.viewport_set(x0, y0, n, n)
            shader.bind()
            shader.uniform_int("origin", (x0, y0))
            shader.uniform_float("scale", 1.0)
            shader.uniform_sampler("src_color", self._scratch[0] if src is None else src)
            self._copy_batch.draw(shader)
