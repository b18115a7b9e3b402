"""The world's ambient occlusion: the camera depth prepass its samples read.

A sample that occludes the world's light (``features.world_occlusion.world_ao_sample``: a one-sample frame, a
frame's first sample) first draws the view depth of what the lit pass will show through the
lit pass's own raster camera into a float target of the film's size; the lit pass's
``WORLD_AO`` variant then marches it for horizons around each fragment (screen-space
ground-truth ambient occlusion, Jimenez et al. 2016; ``shaders/lib/gtao.glsl``).

What goes in: every part the lit pass draws opaque (holdouts included) or dithered (Blend
Mode › Dithered, its alpha from the material, an alpha texture or a compiled node tree, with
the lit pass's hash and alpha offset, so a dithered surface covers the same pixels in both),
with the lit pass's back-face culling, and hair strips (widened toward the camera as the lit
pass widens them); alpha-blended parts are left out, as the lit pass keeps them out of its
depth. The programs are the shadow depth pass's (``shadow_programs.CAMERA_DEPTH``): the camera is its
"tile", and it writes the view depth itself (float32: full precision at any distance) instead
of a map's normalised depth, clipping at the near plane as the lit pass does.

Then ``march`` draws the horizons at half resolution (``AO_HORIZONS``: one march per 2x2
pixels, from one pixel of each block, the horizons not depending on the normal), and
the lit pass upsamples them by nearest depth and integrates them for its own normals
(``lib/gtao.glsl``). A one-sample frame at 960x540 spent three quarters of its time in the
march at full resolution on a software rasteriser.

The targets (R32F view depth, 0 where nothing is drawn, a z-buffer, and the half-resolution
RGBA32F horizons) belong to the renderer and follow the film's size; final renders take them
from the texture pool and give them back.
"""

import numpy as np

from ....shaders.loader import Program
from ...gpu_pool import new_texture
from ...shadows import lightspace
from ..programs import AO_SAMPLER, FRAME_STRUCT, TILE_STRUCT, depth_defines, image_premultiplied_bits
from ..shadow_maps import draw_cutout
from ..shadow_pass import tree_cutout
from ..shadow_programs import shadow_cutout_program, shadow_hair_program, shadow_program, shadow_tree_program

# The horizons of one pixel of each 2x2 block, marched over the prepass (``lib/gtao.glsl``):
# per half-resolution texel, the three slices' packed angle pairs and that pixel's view depth.
AO_HORIZONS = Program(
    name="ao_horizons",
    vertex="fullscreen.vert.glsl",
    fragment="ao_horizons.frag.glsl",
    libs=("lib/gtao.glsl",),
    vertex_in=(("VEC2", "pos"),),
    samplers=(("FLOAT_2D", AO_SAMPLER),),
    uniform_blocks=((FRAME_STRUCT, "frame", 0),),
    outputs=(("VEC4", "out_horizons"),),
    defines=(("WORLD_AO", True),),
)


def half_size(size):
    """The half-resolution target's size for a film of ``size``: one texel per 2x2 block."""
    return ((int(size[0]) + 1) // 2, (int(size[1]) + 1) // 2)


def camera_tile(camera, size, origin):
    """The TILE_STRUCT row of the camera depth prepass: the raster ``camera``'s view (positions
    relative to ``origin``) and projection, and a pixel's world size (at distance 1 for a
    perspective camera) for hair strands a pixel wide."""
    p = np.asarray(camera.projection, np.float64)
    width, height = size
    pixel = 2.0 / max(abs(p[1, 1]) * height, 1e-30)
    return {
        "view": camera.view @ lightspace.from_origin(origin),
        "proj_tex": lightspace.BIAS_MATRIX @ p,
        "near": 0.0,
        "far": 1.0,
        "texel": pixel,
        "texel_per_distance": pixel,
        "size": int(max(width, height)),
        "origin": (0, 0),
    }


def prepass_parts(d, materials, textures):
    """What draw ``d`` puts in the prepass: (solid, cutouts), solid a list of (batch, cull),
    cutouts a list of (batch, cull, material UBO, (alpha texture, bits) or None, TreeCutout or
    None). Alpha-blended parts (not holdouts) are left out."""
    solid, cutouts = [], []
    for index, batch in d.parts:
        mat = d.material(index)
        features = mat.features
        if "ALPHA_BLEND" in features and not d.instance.holdout:
            continue
        cull = bool(mat.cull_camera)
        if "ALPHA_HASHED" not in features or d.instance.holdout:
            solid.append((batch, cull))
        elif mat.tree is not None and "FRAME" not in mat.tree.needs:
            cutouts.append((batch, cull, materials.get(mat), None, tree_cutout(d, mat, materials, textures)))
        elif "alpha" in mat.textures:
            image = mat.textures["alpha"].image
            bits = image_premultiplied_bits(textures.premultiplied, [("alpha", image)])
            cutouts.append((batch, cull, materials.get(mat), (textures.get(image), bits), None))
        elif mat.tree is not None:
            solid.append((batch, cull))  # an alpha the depth pass cannot evaluate: drawn whole
        elif mat.alpha > 0.0:
            cutouts.append((batch, cull, materials.get(mat), None, None))
    return solid, cutouts


class WorldAO:
    """The camera depth prepass of one renderer: its targets and tile block. ``pool``: the
    ``gpu_pool.TexturePool`` its targets come from (final renders), else None."""

    def __init__(self, pool=None):
        self.pool = pool
        self.size = None
        self.texture = None  # R32F view depth (0: nothing drawn), what the lit pass's ao_depth reads
        self.zbuffer = None
        self.horizons = None  # RGBA32F at half resolution, what the lit pass's ao_horizons reads
        self._framebuffer = None
        self._march_framebuffer = None
        self._triangle = None
        self._ubo = None
        self.uploaded = 0  # bytes of tile blocks sent to the GPU since creation

    def ensure(self, size):
        import gpu

        if self.size == tuple(size) and self.texture is not None:
            return
        self.release()
        self.texture = new_texture(self.pool, size, "R32F")
        self.zbuffer = new_texture(self.pool, size, "DEPTH_COMPONENT32F")
        self.horizons = new_texture(self.pool, half_size(size), "RGBA32F")
        self._framebuffer = gpu.types.GPUFrameBuffer(depth_slot=self.zbuffer, color_slots=(self.texture,))
        self._march_framebuffer = gpu.types.GPUFrameBuffer(color_slots=(self.horizons,))
        self.size = tuple(size)

    @property
    def memory_bytes(self):
        if self.size is None:
            return 0
        w, h = half_size(self.size)
        return 8 * self.size[0] * self.size[1] + 16 * w * h

    def march(self, frame_block, shaders, stats):
        """The horizons at half resolution over the prepass just drawn, with the lit pass's
        frame block (``frame_block``: its GPUUniformBuf, this sample's WORLD_AO fields)."""
        import gpu
        from gpu_extras.batch import batch_for_shader

        shader = shaders.get(AO_HORIZONS)
        if self._triangle is None:
            self._triangle = batch_for_shader(shader, "TRIS", {"pos": ((-1, -1), (3, -1), (-1, 3))})
        width, height = half_size(self.size)
        with self._march_framebuffer.bind():
            gpu.state.viewport_set(0, 0, width, height)
            gpu.state.depth_test_set("NONE")
            gpu.state.blend_set("NONE")
            shader.bind()
            shader.uniform_block("frame", frame_block)
            shader.uniform_sampler(AO_SAMPLER, self.texture)
            self._triangle.draw(shader)
        stats.ao_texels += width * height

    def draw(self, draws, camera, size, origin, caches, stats, alpha_offset=0.5):
        """The view depth of ``draws`` (those the camera sees) through the raster ``camera``
        into ``texture`` at the film's ``size``; ``caches``: the renderer's ``GpuCaches``;
        ``alpha_offset``: the sample's, as the lit pass hashes dithered surfaces with it.
        Counted in ``stats`` as the occlusion's prepass; returns its draw calls."""
        drawn = self.draw_depth(draws, camera, size, origin, caches, alpha_offset)
        stats.ao_draws += drawn  # counted apart from the lit pass's ``draws`` and ``passes``
        stats.ao_prepasses += 1
        return drawn

    def draw_depth(self, draws, camera, size, origin, caches, alpha_offset=0.5):
        """``draw`` without counting it (another technique's prepass counts its own); returns
        its draw calls."""
        import gpu

        shaders, materials, textures = caches.shaders, caches.materials, caches.textures

        self.ensure(size)
        width, height = size
        defines = depth_defines("FLOAT32")
        raw = TILE_STRUCT.pack([camera_tile(camera, size, origin)]).tobytes()
        self.uploaded += len(raw)
        if self._ubo is None:
            self._ubo = gpu.types.GPUUniformBuf(raw)
        else:
            self._ubo.update(raw)
        bound = {"culling": None, "draws": 0}

        def culling(cull, det):
            state = (cull, cull and det < 0.0)
            if bound["culling"] != state:
                gpu.state.face_culling_set("BACK" if state[0] else "NONE")
                gpu.state.front_facing_set(state[1])
                bound["culling"] = state

        seen = [d for d in draws if d.instance.camera]
        with self._framebuffer.bind():
            gpu.state.viewport_set(0, 0, width, height)
            self._framebuffer.clear(color=(0.0, 0.0, 0.0, 0.0), depth=1.0)
            gpu.state.depth_test_set("LESS")
            gpu.state.depth_mask_set(True)
            gpu.state.blend_set("NONE")
            shader = shaders.get(shadow_program("FLOAT32", camera=True), defines)
            shader.bind()
            shader.uniform_block("tile", self._ubo)
            parts = {}
            for d in seen:
                if d.instance.hair is None:
                    parts[id(d)] = prepass_parts(d, materials, textures)
            for d in seen:
                if d.instance.hair is not None:
                    continue
                solid, _cutouts = parts[id(d)]
                if not solid:
                    continue
                shader.uniform_float("model", d.model)
                if len(solid) == len(d.parts) and not any(cull for _b, cull in solid):
                    culling(False, d.det)
                    d.whole.draw(shader)  # every part opaque: one draw
                    bound["draws"] += 1
                    continue
                for batch, cull in solid:
                    culling(cull, d.det)
                    batch.draw(shader)
                    bound["draws"] += 1
            strips = [d for d in seen if d.instance.hair is not None]
            if strips:
                culling(False, 1.0)
                hair = shaders.get(shadow_hair_program("FLOAT32", camera=True), defines)
                hair.bind()
                hair.uniform_block("tile", self._ubo)
                for d in strips:
                    hair.uniform_float("model", d.model)
                    hair.uniform_float("hair_texels", 1.0 if d.instance.hair == "STRAND" else 0.0)
                    d.whole.draw(hair)
                    bound["draws"] += 1
            for d in seen:
                if d.instance.hair is not None:
                    continue
                for batch, cull, material_ubo, texture, tree in parts[id(d)][1]:
                    culling(cull, d.det)
                    if tree is not None:
                        program = shadow_tree_program("FLOAT32", tree.tree, camera=True)
                    else:
                        program = shadow_cutout_program("FLOAT32", texture is not None, camera=True)
                    cut = shaders.get(program, defines)
                    draw_cutout(cut, (batch, material_ubo, texture, tree), self._ubo, alpha_offset, d.model, origin)
                    bound["draws"] += 1
            gpu.state.face_culling_set("NONE")
            gpu.state.front_facing_set(False)
            gpu.state.depth_test_set("NONE")
            gpu.state.depth_mask_set(False)
        return bound["draws"]

    def release(self):
        """Give the targets back to the pool (final renders; inside the GPU context) or drop
        them."""
        if self.pool is not None:
            self.pool.give([t for t in (self.texture, self.zbuffer, self.horizons) if t is not None])
        self.texture = self.zbuffer = self.horizons = self._framebuffer = self._march_framebuffer = None
        self.size = None
