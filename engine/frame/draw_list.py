"""The draw list: the frame's mesh instances with their GPU batches, world bounds and level of
detail; the order the lit pass draws them in; which lights reach what the camera sees; and
each instance's light-linking mask."""

import functools
from dataclasses import dataclass

import numpy as np

from ..scene import simplify
from ..scene.extract import Light
from ..scene.materials import Material
from ..shadows import light_bins, lightspace

DEFAULT_MATERIAL = Material()  # for faces whose material slot is empty
# Closed meshes (``extract.closed_outward``) seen from outside their bounds are drawn without
# their back faces, in the lit pass and in shadow maps: those faces are hidden by the mesh's
# own front faces, so the image is the same and the rasteriser sets up half the triangles.
CULL_CLOSED = True
# Object › Shading › Shadow Terminator › Geometry Offset applies where a mesh's facets are at least
# this many pixels across: below it a pixel averages several facets, and no staircase shows, so
# the per-corner stream and its variant are not paid for.
TERMINATOR_MIN_PIXELS = 1.0
_CORNER_BITS = np.array([[i & 1, (i >> 1) & 1, (i >> 2) & 1] for i in range(8)], dtype=bool)  # box corners


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
    geometry: object = None  # the geometry.Geometry drawn whole (None: drawn at a level of detail)
    bounds: np.ndarray = None  # (2, 3) object-space bounds (Generated texture coordinates)
    triangles: int = 0  # triangles of what it draws
    # () -> [(material index, GPUBatch)] with the Shadow Terminator's corner data, built on
    # first call; None where the geometry offset does not apply (offset 0, flat faces only).
    terminator_parts: object = None

    def terminator_features(self, shadowed):
        """The lit-pass features of the instance's Shadow Terminator settings
        (``programs.TERMINATOR_FEATURES``); ``shadowed``: the frame has shadow maps (without
        them the offsets of the shadow point do nothing)."""
        term = self.instance.terminator
        out = set()
        if shadowed and self.terminator_parts is not None:
            out.add("TERMINATOR_OFFSET")
        if shadowed and term.world_normal_offset(self.instance.matrix) > 0.0:
            out.add("TERMINATOR_NORMAL")
        if term.shading_offset > 0.0:
            out.add("TERMINATOR_SHADING")
        return frozenset(out)

    def texture_space(self):
        """Push constants of Blender's Generated coordinates (a compiled node tree's
        ``node_texspace_*``): the object's bounds mapped to [0, 1], a flat axis (of zero
        extent) to 0.5, as Blender's automatic texture space."""
        if self.bounds is None:
            lo, hi = np.zeros(3), np.ones(3)
        else:
            lo, hi = np.asarray(self.bounds[0], np.float64), np.asarray(self.bounds[1], np.float64)
        half = (hi - lo) * 0.5
        half = np.where(half == 0.0, 1.0, np.maximum(half, 1e-5))
        scale = 0.5 / half
        offset = 0.5 - (hi + lo) * 0.5 * scale
        return {
            "node_texspace_scale": tuple(float(x) for x in scale),
            "node_texspace_offset": tuple(float(x) for x in offset),
        }

    def tree_uniforms(self, tree):
        """The per-draw push constants compiled node tree ``tree`` reads of this instance."""
        out = self.texture_space() if "GENERATED" in tree.needs else {}
        if "OBJECT_INFO" in tree.needs:
            out["node_object_color"] = tuple(float(c) for c in self.instance.color)
            out["node_object_random"] = float(self.instance.random)
        return out

    def material(self, index):
        materials = self.instance.materials
        mat = materials[index] if 0 <= index < len(materials) else None
        return mat or DEFAULT_MATERIAL


def draw_list(snapshot, batches, stats, origin, camera=None, settings=None, size=None):
    """The frame's instances with their batches (``batches.Batches``). Per-instance numbers (sign of the matrix, world
    bounds, level of detail) are computed for all instances at once. Model matrices reach the
    GPU relative to ``origin`` (the frame origin)."""
    from mathutils import Matrix

    kept = [(inst, snapshot.geometry[inst.key]) for inst in snapshot.instances if inst.key in snapshot.geometry]
    draws = []
    if kept:
        matrices = np.stack([inst.matrix for inst, _geo in kept])
        bounds = np.stack([geo.bounds for _inst, geo in kept])
        dets = np.linalg.det(matrices[:, :3, :3])
        local = np.where(_CORNER_BITS[None], bounds[:, None, 1], bounds[:, None, 0])  # (n, 8, 3)
        corners = np.einsum("nij,nkj->nki", matrices[:, :3, :3], local) + matrices[:, None, :3, 3]
        levels = _levels(kept, matrices, bounds, corners, camera, settings, size)
        facets = _facet_pixels(kept, matrices, bounds, corners, camera, size)
        for i, (inst, geo) in enumerate(kept):
            lod = simplify.simplified(geo, levels[i]) if levels[i] is not None else None
            if lod is not None:
                key = (inst.key, geo.serial, levels[i])
                whole, parts = batches.level(key, lod)
                identity = (inst.key, inst.matrix.tobytes(), geo.serial, levels[i])
                stats.simplified += 1
            else:
                key = (inst.key, geo.serial)
                whole, parts = batches.get(inst.key, geo)
                identity = (inst.key, inst.matrix.tobytes(), geo.serial)
            model = inst.matrix.copy()
            model[:3, 3] -= origin
            model = Matrix(model.tolist())
            draw = Draw(inst, whole, parts, model, float(dets[i]), identity, corners[i])
            draw.geometry = geo if lod is None and inst.hair is None else None  # strips have no levels
            draw.bounds = bounds[i]
            draw.triangles = (lod or geo).triangle_count
            if inst.terminator.geometry_offset > 0.0 and (lod or geo).smooth and facets[i] >= TERMINATOR_MIN_PIXELS:
                draw.terminator_parts = functools.partial(batches.terminator, key, lod or geo)
            closed = CULL_CLOSED and geo.closed and lod is None  # a level is not tested for closedness
            draw.closed = closed and not any(draw.material(m).uses_alpha for m, _b in parts)
            draws.append(draw)
            stats.triangles += (lod or geo).triangle_count
    return draws


def _facet_pixels(kept, matrices, bounds, corners, camera, size):
    """Each instance's typical facet width in pixels at its point nearest the camera (an edge of
    a mesh of T triangles over its bounds' largest side E: about 2 E / sqrt(T)); infinite where
    it is unknown (no camera, through the near plane)."""
    out = np.full(len(kept), np.inf)
    if camera is None or size is None:
        return out
    per_depth, constant = lightspace.pixel_footprint(camera.projection, camera.is_ortho, *size)
    view = np.asarray(camera.view, dtype=np.float64)
    nearest = np.min(-(corners @ view[2, :3] + view[2, 3]), axis=1)
    pixel = per_depth * np.maximum(nearest, 0.0) + constant
    stretch = np.linalg.svd(matrices[:, :3, :3], compute_uv=False)[:, 0]
    extent = np.max(bounds[:, 1] - bounds[:, 0], axis=1)
    count = np.array([max(geo.triangle_count, 1) for _inst, geo in kept], np.float64)
    edge = 2.0 * extent * stretch / np.sqrt(count)
    with np.errstate(divide="ignore", invalid="ignore"):
        facets = edge / pixel
    return np.where((nearest > 0.0) & (pixel > 0.0) & np.isfinite(facets), facets, np.inf)


def _levels(kept, matrices, bounds, corners, camera, settings, size):
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
        if geo.uvs is not None or geo.colors is not None or geo.tangents is not None or geo.strands is not None:
            continue  # its materials read more than positions and normals, or hair strips
        if any(m is not None and m.uses_alpha for m in inst.materials):
            continue
        levels[i] = simplify.level_for(float(extent[i]), float(stretch[i]), float(nearest[i]), footprint, pixels)
    return levels


def corners_of(draws):
    """(n, 8, 3) world corners of the draws' bounds."""
    return np.stack([d.corners for d in draws]) if draws else np.zeros((0, 8, 3))


def frame_light_rects(lights, draws, camera, width, height, reach=0.0, receivers=None):
    """The screen rectangles of a frame's lights, once a frame (``light_bins.screen_rects``
    from the unjittered ``camera``): each light's influence padded by how far its samples move
    it (``light_bins.light_reach``), every rectangle by ``reach`` pixels (the camera's offsets
    over the frame's samples). Returns (per light its rectangle or None, the rectangle of a
    light without influence: a sun, a point, a direction of the world), or None without
    draws or lights. ``receivers``: boxes beyond the draws that take light (``FramePlan.receivers``)."""
    if not draws:
        return None
    lo, hi = _bounds(draws, receivers)
    stand_in = Light(type="SUN", color=np.zeros(3), matrix=np.eye(4), radius=0.0)
    rects = light_bins.screen_rects(
        [*lights, stand_in],
        camera.projection @ camera.view,
        lo,
        hi,
        width,
        height,
        pads=[light_bins.light_reach(lt) for lt in lights] + [0.0],
        pixel_pad=reach,
    )
    return rects[:-1], rects[-1]


def _bounds(draws, receivers=None):
    """(lo, hi) world corners of the draws' bounds and of ``receivers`` (n, 8, 3) if any."""
    corners = np.concatenate([d.corners for d in draws])
    if receivers is not None and len(receivers):
        corners = np.concatenate([corners, np.asarray(receivers, np.float64).reshape(-1, 3)])
    return corners.min(axis=0), corners.max(axis=0)


def lights_in_view(lights, draws, camera, width, height, stats, frame=None, receivers=None):
    """The lights that can light a visible surface, with the screen rectangle each can reach
    (``light_bins.screen_rects``); a light that reaches nothing the camera sees gets no shadow
    map and no shading. ``frame``: ``frame_light_rects`` of the frame's lights, which the
    first ``len(frame[0])`` of ``lights`` are at this sample (moved within their reach), the
    rest lights without influence (the world's directions): nothing is computed per sample."""
    if not draws or not lights:
        return lights, None
    if frame is not None:
        known, anywhere = frame
        rects = [known[i] if i < len(known) else anywhere for i in range(len(lights))]
    else:
        lo, hi = _bounds(draws, receivers)
        rects = light_bins.screen_rects(lights, camera.projection @ camera.view, lo, hi, width, height)
    keep = [i for i, r in enumerate(rects) if r is not None]
    stats.lights_out_of_view = len(lights) - len(keep)
    return [lights[i] for i in keep], [rects[i] for i in keep]


def light_masks(draws, lights, order):
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


def front_to_back(draws, camera):
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


def longest_ray(draws):
    """The longest ray a screen-space trace follows (reflections, refraction): the diagonal of
    the box around what the frame draws (0 where nothing finite is drawn)."""
    corners = corners_of(draws).reshape(-1, 3)
    corners = corners[np.all(np.isfinite(corners), axis=1)]
    if len(corners) == 0:
        return 0.0
    diagonal = float(np.linalg.norm(corners.max(axis=0) - corners.min(axis=0)))
    return diagonal if np.isfinite(diagonal) else 0.0


# Principled roughness from which lobes are not traced (lit_world.glsl WORLD_RATIO_ROUGH; from
# SSR_FADE, 0.4, their rays fade out): what the reflections, a Plane probe's capture and the
# cube maps serve.
TRACED_BELOW = 0.5


def reflective_material(mat):
    """Whether a surface of material ``mat`` (``materials.Material``; None: the default, of
    roughness 0.5) may have a lobe sharp enough to be traced."""
    if mat is None or mat.holdout:
        return False
    if mat.tree is not None or "roughness" in mat.textures:
        return True  # its roughness is known per pixel only
    if not (mat.specular > 0.0 or mat.metallic > 0.0):
        return False
    return float(mat.roughness) < TRACED_BELOW


def reflective_materials(draws):
    """Whether any draw the camera sees has a reflective material (``reflective_material``)."""
    return any(reflective_material(m) for d in draws if d.instance.camera for m in (d.instance.materials or (None,)))
