"""Shadow planning: which maps a frame needs, fitted how (numpy only; the depth pass that
draws them is ``frame.shadow_maps``).

Every map of a frame is a square tile of one atlas texture, so the lit pass binds a single
sampler whatever the number and kind of lights:
  sun    one orthographic tile fitted to the receivers the camera sees and the casters that
         can shadow them, texel-snapped;
  spot   one perspective tile covering the cone, near/far fitted to the casters inside it;
  point  up to six perspective tiles (cube faces); a face with no caster in reach is skipped;
  area   shadowed like a point light at its centre (softness from its size), without the
         cube face that looks wholly behind it (an area light emits forward only).
A light with ``use_shadow`` off, or with no caster in reach, gets no tile and costs nothing.
Tiles whose fit and casters did not change since the last frame are not redrawn.
"""

import math
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from . import light_bins, lightspace

# Maps a frame can hold: the lit pass's ShadowTile block (160 bytes each) stays within the 16 KiB every
# GL implementation allows a uniform block. Maps share the atlas by size, so the texels are what they hold.
MAX_SHADOW_TILES = 96


@dataclass
class Tile:
    fit: lightspace.Fit
    casters: np.ndarray  # indices into the frame's draws that can cast into this tile
    size: int = 0  # texels per side of this map
    origin: tuple = (0, 0)  # its lower-left texel in the atlas (ShadowAtlas.place)
    held: object = None  # points of the visible receivers inside it, when planning found them

    def record(self, origin=None):
        """The tile's TILE_STRUCT row; ``origin``: the frame origin its view takes positions
        relative to (the map's content does not depend on it)."""
        f = self.fit
        return {
            "view": f.view if origin is None else f.view @ lightspace.from_origin(origin),
            "proj_tex": lightspace.BIAS_MATRIX @ f.proj,
            "near": f.near,
            "far": f.far,
            "texel": f.texel,
            "texel_per_distance": f.texel_per_distance,
            "size": self.size,
            "origin": self.origin,
        }


@dataclass
class LightShadow:
    mode: str  # 'SINGLE' | 'CUBE' | 'CASCADE'
    tiles: list = field(default_factory=list)  # per face, cascade (or one): index into plan.tiles, or -1
    splits: tuple = ()  # CASCADE: the view depth where each cascade ends
    blend: tuple = ()  # CASCADE: per split, the depth before it over which the next cascade fades in


@dataclass
class ShadowPlan:
    tiles: list = field(default_factory=list)
    lights: dict = field(default_factory=dict)  # light index -> LightShadow
    unshadowed: int = 0  # lights that cast shadows but found no room in the atlas


def _near_bound(position, lo, hi, half_fov):
    """A lower bound of the view-axis distance of any point of the boxes [lo, hi] inside a
    square frustum of half-angle ``half_fov`` at ``position`` (distance to the box, shrunk by
    the frustum's widest corner angle)."""
    d = np.linalg.norm(np.maximum(0.0, np.maximum(lo - position, position - hi)), axis=1)
    return float(d.min()) / math.sqrt(1.0 + 2.0 * math.tan(half_fov) ** 2)


CUBE_PAD_FRACTION = 1.0 / 16.0


@dataclass(frozen=True)
class Density:
    """How finely the camera sees: a screen pixel at view depth z is ``per_depth * z +
    constant`` wide in the world (``lightspace.pixel_footprint``); ``camera_view`` maps world
    to view space; a map should give each pixel ``texels_per_pixel`` texels across."""

    camera_view: np.ndarray
    per_depth: float
    constant: float
    texels_per_pixel: float


MIN_MAP_SIZE = 16  # the smallest map density sizing chooses


def needed_size(tile, size, receivers, density, per_pixel):
    """Texels per side that ``tile`` (planned with ``size``) needs for ``per_pixel`` texels
    across every screen pixel of the visible receivers it holds: a power of two in
    [MIN_MAP_SIZE, size], or ``size``. The finest need is at a vertex of what it holds (the
    ratio of texel to pixel width is linear-fractional in the position)."""
    return needed_sizes([tile], size, receivers, density, per_pixel)[0]


def needed_sizes(tiles, size, receivers, density, per_pixel):
    """``needed_size`` of each of ``tiles`` (None: ``size``), the visible receivers of those
    that do not hold them already (``Tile.held``: the uncropped ones) clipped to all their
    frustums at once."""
    if per_pixel <= 0.0:
        return [size] * len(tiles)
    missing = [n for n, t in enumerate(tiles) if t is not None and t.held is None]
    regions = [light_bins.frustum_planes(tiles[n].fit.view_proj) for n in missing]
    clipped = dict(zip(missing, lightspace.pieces_in_many(regions, [receivers.whole] * len(regions), receivers.pieces)))
    sizes = []
    for n, tile in enumerate(tiles):
        if tile is None:
            sizes.append(size)
        elif tile.held is not None:
            sizes.append(_needed(tile.fit, tile.held, size, density, per_pixel))
        elif not clipped[n]:
            sizes.append(size)
        else:
            sizes.append(_needed(tile.fit, np.concatenate(clipped[n]), size, density, per_pixel))
    return sizes


def _needed(fit, points, size, density, per_pixel):
    """``needed_size`` of a map of ``fit`` that holds the receivers' ``points``."""
    view = density.camera_view
    z = np.maximum(-(points @ view[2, :3] + view[2, 3]), 0.0)
    pixel = density.per_depth * z + density.constant
    if fit.texel_per_distance > 0.0:
        texel = fit.texel_per_distance * np.maximum(-(points @ fit.view[2, :3] + fit.view[2, 3]), 0.0)
    else:
        texel = np.full(len(points), fit.texel)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = float(np.max(texel / pixel)) * per_pixel
    if not math.isfinite(ratio) or ratio >= 1.0:
        return size
    need = max(ratio * size, float(MIN_MAP_SIZE))
    return min(size, 2 ** math.ceil(math.log2(need) - 1e-9))


class Eye(NamedTuple):
    """Where a perspective map looks from: the light's ``position``, the unit ``forward`` it
    looks along and the ``fov`` (radians) of its square frustum."""

    position: np.ndarray
    forward: np.ndarray
    fov: float


class Boxes(NamedTuple):
    """The boxes a map is planned over: ``corners`` (N, 8, 3) and their (N, 3) bounds."""

    corners: np.ndarray
    lo: np.ndarray
    hi: np.ndarray

    @classmethod
    def of(cls, corners):
        return cls(corners, corners.min(axis=1), corners.max(axis=1))


class Crop(NamedTuple):
    """What a perspective map is cropped to (``perspective_tile``): the visible ``receivers``
    (``lightspace.Receivers``) and ``flat_free``, the flat boxes that shadow nothing (None:
    not tested)."""

    receivers: object
    flat_free: np.ndarray = None
    windows: dict = None  # ``ViewFit.windows``


class _Frustum(NamedTuple):
    """A perspective map's frustum before it is cropped: its view matrix, field of view and depth range."""

    view: np.ndarray
    fov: float
    near: float
    far: float


def perspective_tile(eye, boxes, map_size, kernel=0.0, soft_radius=0.0, crop=None, memo=None):
    """A perspective tile from ``eye`` (an ``Eye``) over ``boxes`` (``Boxes``), or None
    without casters in it.

    ``kernel`` (texels) or ``soft_radius`` (world: a PCSS light's radius) widen the map past
    the eye's fov by the widest filter kernel it can be read with, so a filter near its edge
    reads texels of this map instead of "nothing there": cube faces then meet without a lit
    seam. A PCSS kernel is widest for the nearest caster: radius / near, in texels of the map;
    the widening stops at CUBE_PAD_FRACTION of the map per side (wider penumbrae may still
    show a faint seam).

    With ``crop`` (a ``Crop``: what the camera sees) the map is cropped to the window, in the
    light's view, of the visible receivers that some caster can shadow: the casters' window
    (flat boxes that shadow nothing are not casters), widened by how far a penumbra reaches
    out of it, cut to the receivers' window. No visible receiver in reach of a caster: no map.

    ``memo`` (a dict kept for one light and frame) holds what does not depend on the map's
    size, for planning the same light again at another size."""
    return perspective_tiles([eye], boxes, [map_size], kernel, soft_radius, crop, memo)[0]


class _Face(NamedTuple):
    """A perspective map fitted before it is cropped (``_face_fit``): its ``frustum`` (a
    ``_Frustum``), the boxes ``inside`` it, its ``size`` and the ``pad`` texels it is widened
    by, and the key of its eye's direction in the memo."""

    frustum: _Frustum
    inside: np.ndarray
    size: int
    pad: float
    face: bytes


def perspective_tiles(eyes, boxes, sizes, kernel=0.0, soft_radius=0.0, crop=None, memo=None):
    """``perspective_tile`` of each of ``eyes`` at its size in ``sizes`` (a point light's cube
    faces), with one ``memo``: each map is fitted alone, then all are cropped together, the
    visible receivers and the casters clipped to every frustum at once
    (``lightspace.pieces_in_many``), the same maps as one at a time. A list of tiles (None
    where ``perspective_tile`` gives none)."""
    memo = {} if memo is None else memo
    kept = None if crop is None else crop.windows
    if kept is not None and len(eyes) > 1 and len(kept) + len(eyes) >= _KEPT_WINDOWS:
        # A crop may empty the kept windows (``_crops``): one map after the other then, as
        # each one's crop finds what the one before it left.
        return [perspective_tiles([e], boxes, [z], kernel, soft_radius, crop, memo)[0] for e, z in zip(eyes, sizes)]
    fits = [_face_fit(eye, boxes, size, kernel, soft_radius, memo) for eye, size in zip(eyes, sizes, strict=True)]
    tiles = [None] * len(fits)
    live = [n for n, f in enumerate(fits) if f is not None]
    if crop is None:
        for n in live:
            tiles[n] = _uncropped(fits[n])
        return tiles
    keys = {n: (fits[n].face, "window", *fits[n].frustum[1:]) for n in live}
    missing = [n for n in live if keys[n] not in memo]
    frustums, insides = [fits[n].frustum for n in missing], [fits[n].inside for n in missing]
    found = _windows(frustums, boxes.corners, insides, crop, soft_radius)
    for n, window in zip(missing, found, strict=True):
        memo[keys[n]] = window
    cropped = _crops([fits[n] for n in live], boxes.corners, crop.receivers, [memo[keys[n]] for n in live], kept)
    for n, got in zip(live, cropped, strict=True):
        if got is _NOTHING:
            continue
        if got is None:
            tiles[n] = _uncropped(fits[n])
            continue
        proj, per_distance, inside, far, held = got
        view, _fov, near, _far = fits[n].frustum
        tiles[n] = Tile(lightspace.Fit(view, proj, near, far, texel_per_distance=per_distance), inside)
        tiles[n].held = held
    return tiles


def _face_fit(eye, boxes, map_size, kernel, soft_radius, memo):
    """``eye``'s map over ``boxes`` fitted and widened by its filter's pad (``perspective_tile``),
    not cropped: a ``_Face``, or None without casters in it."""
    position, forward, fov = eye
    corners = boxes.corners
    face = np.asarray(forward, dtype=np.float64).tobytes()
    reach = float(np.linalg.norm(corners.reshape(-1, 3) - position, axis=1).max()) * 1.01
    if not np.isfinite(reach) or reach <= 0.0:
        return None
    if (face, "view") not in memo:
        memo[face, "view"] = lightspace.look_at(position, forward)
    view = memo[face, "view"]

    def fitted(fov):
        key = (face, "fit", fov)
        if key not in memo:
            memo[key] = fitted_now(fov)
        return memo[key]

    def fitted_now(fov):
        probe = lightspace.perspective(fov, 1.0, reach * 1e-6, reach) @ view
        inside = np.nonzero(lightspace.boxes_in_frustum(probe, corners))[0]
        if len(inside) == 0:
            return None
        z = -(corners[inside].reshape(-1, 3) @ view[:3, :3].T + view[:3, 3])[:, 2]
        far = float(z.max()) * 1.01
        if far <= 0.0:
            return None
        near = max(_near_bound(position, boxes.lo[inside], boxes.hi[inside], fov / 2.0) * 0.99, far * 1e-5)
        return inside, near, far

    got = fitted(fov)
    if got is None:
        return None
    size = max(int(map_size), 1)
    if kernel > 0.0 or soft_radius > 0.0:
        per_distance = 2.0 * math.tan(fov / 2.0) / size  # a texel's width at distance 1
        widest = soft_radius / (got[1] * per_distance) if soft_radius > 0.0 else kernel
        pad = min(widest, CUBE_PAD_FRACTION * size) + 1.0
        if 2.0 * pad < size:
            fov = 2.0 * math.atan(math.tan(fov / 2.0) * size / (size - 2.0 * pad))
            got = fitted(fov) or got
    else:
        pad = 0.0
    inside, near, far = got
    return _Face(_Frustum(view, fov, near, far), inside, size, pad, face)


def _uncropped(fit):
    """The tile of a ``_Face`` over its whole frustum."""
    view, fov, near, far = fit.frustum
    proj = lightspace.perspective(fov, 1.0, near, far)
    texel = 2.0 * math.tan(fov / 2.0) / fit.size
    return Tile(lightspace.Fit(view, proj, near, far, texel_per_distance=texel), fit.inside)


_NOTHING = object()  # _crops: no visible receiver in reach of a caster
# ``ViewFit.windows`` is emptied past this many (lights and sizes come and go while the view moves).
_KEPT_WINDOWS = 1024


def _windows(frustums, corners, insides, crop, soft_radius):
    """Per perspective map ``frustums[k]`` (a ``_Frustum``) and the boxes ``insides[k]`` in
    it: the window (tangent units, lower and upper corner) of the visible receivers some of
    those casters can shadow, with those casters; or _NOTHING. Does not depend on the map's
    size. Every map's receivers, then every map's casters, are clipped at once."""
    receivers, flat_free = crop.receivers, crop.flat_free
    planes = [light_bins.frustum_planes(lightspace.perspective(f.fov, 1.0, f.near, f.far) @ f.view) for f in frustums]
    seen = lightspace.pieces_in_many(planes, [receivers.whole] * len(planes), receivers.pieces)
    out = [_NOTHING] * len(frustums)
    staged = []
    for n, (frustum, pieces, inside) in enumerate(zip(frustums, seen, insides, strict=True)):
        if not pieces:
            continue
        r_lo, r_hi = lightspace.window(np.concatenate(pieces), frustum.view, frustum.near)
        casters = inside if flat_free is None else inside[~flat_free[inside]]
        if len(casters):
            staged.append((n, r_lo, r_hi, casters))
    footprints = lightspace.pieces_in_many([planes[n] for n, *_ in staged], [corners[c] for *_, c in staged])
    for (n, r_lo, r_hi, casters), footprint in zip(staged, footprints, strict=True):
        if not footprint:
            continue
        view, fov, near, _far = frustums[n]
        half = math.tan(fov / 2.0)
        c_lo, c_hi = lightspace.window(np.concatenate(footprint), view, near)
        spread = soft_radius / near  # how far (tangent units) a penumbra reaches out of a caster's window
        w_lo = np.maximum(np.maximum(r_lo, c_lo - spread), -half)
        w_hi = np.minimum(np.minimum(r_hi, c_hi + spread), half)
        if not np.any(w_hi < w_lo):
            out[n] = (w_lo, w_hi, casters)
    return out


def _crops(faces, corners, receivers, windows, kept=None):
    """Each map of ``faces`` (``_Face``) cut to what it must hold (see ``perspective_tile``):
    (projection, texel per distance, casters, far, the visible receivers' points it holds),
    None when cropping gains nothing, or _NOTHING. ``windows``: ``_windows``' answers.
    ``kept`` (``ViewFit.windows``): the window and far plane an earlier frame cut this same
    frustum (eye, direction, depth range, size) to are taken again while they hold this
    one's, and this one's are kept there for the next frame. The receivers every map holds
    are clipped to them all at once."""
    out = [None] * len(faces)
    staged = []
    for n, (fit, window) in enumerate(zip(faces, windows, strict=True)):
        if window is _NOTHING:
            out[n] = _NOTHING
            continue
        cut = _crop_window(fit, corners, window, kept)
        if cut is None or cut is _NOTHING:
            out[n] = cut
            continue
        staged.append((n, cut))
    views = [faces[n].frustum.view for n, _cut in staged]
    regions = [light_bins.frustum_planes(cut[0] @ view) for (_n, cut), view in zip(staged, views, strict=True)]
    held = lightspace.pieces_in_many(regions, [receivers.whole] * len(regions), receivers.pieces)
    for (n, cut), view, points in zip(staged, views, held, strict=True):
        if not points:
            out[n] = _NOTHING
            continue
        out[n] = _crop_depth(faces[n], cut, view, np.concatenate(points), kept)
    return out


def _crop_window(fit, corners, window, kept):
    """``_crops``' first part for one map: its square window snapped to texels (or the one
    ``kept`` holds), its off-centre projection and the casters whose window meets it; as
    (projection, (left, right, bottom, top), texel, casters, slot, old), or None / _NOTHING."""
    view, fov, near, far = fit.frustum
    size, pad = fit.size, fit.pad
    w_lo, w_hi, casters = window
    half = math.tan(fov / 2.0)
    # Square texels, the extent quantised in 2^(1/4) steps and the window snapped to whole
    # texels, so small camera moves do not move texel boundaries; ``pad`` texels each side.
    extent = max(float(np.max(w_hi - w_lo)), 2.0 * half * 1e-4)
    extent = 2.0 ** (math.ceil(math.log2(extent) * 4.0) / 4.0)
    total = extent * size / max(size - 2.0 * max(pad, 2.0), 1.0)
    if total >= 2.0 * half:
        return None
    texel = total / size
    centre = np.floor(0.5 * (w_lo + w_hi) / texel) * texel
    left, bottom = centre - 0.5 * total
    right, top = centre + 0.5 * total
    slot = old = None
    if kept is not None:
        slot = (view.tobytes(), near, far, size, fov)
        old = kept.get(slot)
        holds = old is not None and old[0] <= left and old[1] >= right and old[2] <= bottom and old[3] >= top
        if holds and old[1] - old[0] <= 2.0 * (right - left):  # and at most twice as coarse
            left, right, bottom, top = old[:4]
            texel = (right - left) / size
        else:
            old = None
    # Casters whose window misses the map's cannot shadow into it (those reaching behind the
    # light's near plane are kept).
    q = corners[casters] @ view[:3, :3].T + view[:3, 3]
    depth = -q[..., 2]
    front = np.all(depth >= near * 0.5, axis=1)
    uv = q[..., :2] / np.maximum(depth, near * 0.5)[..., None]
    overlap = np.all((uv.min(axis=1) <= (right, top)) & (uv.max(axis=1) >= (left, bottom)), axis=1)
    casters = casters[~front | overlap]
    if len(casters) == 0:
        return _NOTHING
    proj = lightspace.off_center_perspective(left, right, bottom, top, near, far)
    return proj, (left, right, bottom, top), texel, casters, slot, old


def _crop_depth(fit, cut, view, held, kept):
    """``_crops``' last part for one map: nothing beyond the farthest visible receiver in the
    map's window (``held``, its points) needs a depth. The far plane is quantised up in
    2^(1/8) steps of its ratio to the near one, as the extent is, so a moving view that sees
    a little more or less depth keeps the map (and its content key)."""
    proj, (left, right, bottom, top), texel, casters, slot, old = cut
    _view, _fov, near, far = fit.frustum
    deepest = -float((held @ view[2, :3] + view[2, 3]).min())
    if near < deepest * 1.01 < far:
        far = min(far, near * 2.0 ** (math.ceil(math.log2(deepest * 1.01 / near) * 8.0) / 8.0))
        if old is not None and far <= old[4]:
            far = old[4]
        proj = lightspace.off_center_perspective(left, right, bottom, top, near, far)
    if slot is not None:
        if len(kept) >= _KEPT_WINDOWS:
            kept.clear()
        kept[slot] = (left, right, bottom, top, far)
    return proj, texel, casters, far, held


# A cube face's frustum reaches 54.74 degrees (its corners) from its axis; it lies wholly
# behind an area light when its axis is within 90 - 54.74 degrees of the light's back.
_BEHIND_COS = math.cos(math.radians(90.0 - math.degrees(math.atan(math.sqrt(2.0)))))


def behind_area_light(face_forward, light_direction):
    """Whether a whole cube face looks into the half-space behind an area light, which it
    does not light (it emits forward only): that face needs no map."""
    return float(np.dot(face_forward, -np.asarray(light_direction))) >= _BEHIND_COS


@dataclass(frozen=True)
class MapOptions:
    """How a frame's maps are made (``plan_shadows``). ``map_size``: texels a side of a map at
    most. ``cascades``: the cascades a sun fitted to the view splits its depth range into (0:
    chosen from the range, see ``lightspace.cascade_count``). ``kernel``: the radius (texels)
    of the scene's fixed shadow filter; ``pcss``: the scene's filter is PCSS (lights sampled
    over their extent always are); maps are widened by what their filter reads. A direction
    of the world's light (``light.world``) gets one map fitted to everything the camera sees
    (no cascades) of at most ``world_map_size`` texels a side. ``reflective``: the maps are
    also reflective shadow maps (the diffuse bounce), whose texels are the senders of bounced
    light: every box counts as a caster (flat ones too), so a map covers every visible
    receiver its light reaches, not only those a caster can shadow."""

    map_size: int
    cascades: int = 0
    kernel: float = 2.0
    pcss: bool = False
    world_map_size: int = None
    reflective: bool = False


@dataclass(frozen=True)
class ViewFit:
    """What the maps are fitted to (``plan_shadows``). ``view_corners``: the camera frustum's
    corners, to fit suns tightly to what the camera sees (all geometry when None). With
    ``camera`` (an ``extract.Camera``) a sun splits the visible depth range into cascades,
    each fitted to its slice; ``depth_range``: the camera's visible (near, far), when the
    caller already has it. ``receivers``: ``lightspace.visible_receivers`` of the camera, when
    the caller has them. ``density`` (a ``Density``): each light's maps get the fewest texels
    (a power of two, at most the map size) that still give every visible receiver they hold
    that many texels per screen pixel (times the fixed filter's radius: its blur stays within
    half a pixel); the light is then planned again at that size. ``sun_parts``:
    ``lightspace.view_parts(corners, view_corners)``, when the caller keeps them for the frame
    (every sun fitted to the whole view reads them; else once a plan; with ``extra``, of the
    geometry's boxes and then those). ``extra``: boxes (n, 8, 3) that take light and cast
    none (the media, ``frame/features/volumes.py``): suns are fitted to them as to the
    geometry (``receivers`` should hold them for the other lights). ``windows``: a dict the
    caller keeps between navigation frames (while the view moves): a cropped perspective map
    keeps the window, and depth, an earlier frame cropped it to while they still hold what
    this view needs of it, so the map's fit, and its content, do not change (``_crop``).
    None elsewhere: a frame's maps then depend on that frame's view alone. ``flat``: a
    ``lightspace.FlatCasters`` of the plan's boxes the caller keeps for its frame (every
    light, every sample, tests the same flat boxes), else one a plan. ``slices``: the sun's
    cascade slices (``cascade_slices``) when the caller keeps them for its frame."""

    view_corners: np.ndarray = None
    camera: object = None
    depth_range: tuple = None
    receivers: object = None
    density: Density = None
    sun_parts: tuple = None
    extra: np.ndarray = None
    windows: dict = None
    flat: object = None
    slices: list = None


@dataclass(frozen=True)
class FrameShare:
    """What the samples of one frame share of its first plan (``plan_shadows``).

    ``known_sizes``: {light index: texels a side of each of its maps} (``frame_sizes`` of the
    frame's first plan): those lights are planned once, at those sizes, with no density pass;
    so every sample of a frame draws a light's maps at one size, and planning a further
    sample costs one fit per map, not two. ``cones``: {light index: tangent of the widest
    angle its samples turn it} for suns: their maps are fitted to hold every direction of that
    cone (``fit_sun_to_view(cone=)``), as the frame's first plan does for the suns its samples
    shear. ``reaches``: {light index: how far its sampled points lie from its centre} for
    spot, point and area lights: their maps are planned over the scene's boxes and receivers
    grown by that much (``lightspace.dilated_boxes``), so they hold what any of those points
    needs, from the same window, once the eye moves there (``lightspace.moved``).
    ``hinted_sizes``: {light index: map sizes} a light planned at density keeps wherever the
    size density asks for is within SIZE_HYSTERESIS of it (navigation frames: the sizes of the
    last one that planned, so a moving view that needs a little more or less detail keeps its
    maps' sizes, and with them their places in the atlas and their content).
    ``derived``: {light index: (mode, tiles, position) of the frame's first plan}: those
    lights are not planned again, each tile is the first plan's sheared to the sun's direction
    or moved to the light's position (planning a sample costs a matrix product)."""

    known_sizes: dict = None
    hinted_sizes: dict = None
    cones: dict = None
    reaches: dict = None
    derived: dict = None


@dataclass
class _Scene:
    """What every light of one ``plan_shadows`` call is planned over: the boxes, the options
    and view, the sun's cascade slices and what the camera sees."""

    boxes: Boxes
    options: MapOptions
    view: ViewFit
    slices: list
    receivers: object
    sun_parts: tuple  # what the camera sees of every box, once a sun fitted to the whole view needs it
    flat: lightspace.FlatCasters  # the flat boxes' test of every light

    def parts(self):
        if self.sun_parts is None:
            corners, extra = self.boxes.corners, self.view.extra
            if extra is not None and len(extra):
                corners = np.concatenate([corners, np.asarray(extra, np.float64).reshape(-1, 8, 3)])
            self.sun_parts = lightspace.view_parts(corners, self.view.view_corners)
        return self.sun_parts


@dataclass(frozen=True)
class _Job:
    """One light as it is planned: ``flat_free`` (flat boxes that shadow nothing under it, or
    None: not tested), ``memo`` (``perspective_tile``'s, kept for the light), its sun ``cone``
    and its ``reach`` (``FrameShare``), and whether its maps are read with PCSS (``soft``: the
    scene's filter is PCSS, or the light is sampled over its extent)."""

    light: object
    flat_free: np.ndarray
    memo: dict
    cone: float
    reach: float
    soft: bool


def plan_shadows(lights, corners, options, view=None, share=None):
    """Decide the maps of a frame. ``corners``: (N, 8, 3) world corners of every drawn
    instance's bounds; ``options`` (``MapOptions``): how the maps are made; ``view``
    (``ViewFit``): what they are fitted to (all geometry when None); ``share``
    (``FrameShare``): what a frame's later samples take from its first plan.
    Tiles carry the size they were planned with.
    Returns a ShadowPlan; tiles beyond MAX_SHADOW_TILES are not planned (``plan.unshadowed``
    counts those lights, which render unshadowed)."""
    view = ViewFit() if view is None else view
    share = FrameShare() if share is None else share
    plan = ShadowPlan()
    corners = np.asarray(corners, dtype=np.float64).reshape(-1, 8, 3)
    if len(corners) == 0:
        return plan
    seen = corners if view.extra is None else np.concatenate([corners, np.asarray(view.extra).reshape(-1, 8, 3)])
    slices = view.slices
    if slices is None:
        slices = cascade_slices(seen, view.view_corners, view.camera, options.cascades, view.depth_range)
    # What the camera sees, once for every spot, point and area map of the frame.
    receivers = view.receivers
    if receivers is None and view.camera is not None:
        receivers = lightspace.visible_receivers(corners, view.camera.projection @ view.camera.view)
    flat = view.flat if view.flat is not None and view.flat.count == len(corners) else lightspace.FlatCasters(corners)
    scene = _Scene(Boxes.of(corners), options, view, slices, receivers, view.sun_parts, flat)
    for i, light in enumerate(lights):
        if not light.use_shadow:
            continue
        if share.derived is not None and i in share.derived and not light.world:
            mode, tiles = _derived_tiles(light, *share.derived[i])
        else:
            mode, tiles = _planned_tiles(scene, share, i, light)
        _add(plan, i, mode, tiles, slices, view.depth_range)
    return plan


def _derived_tiles(light, mode, first, position):
    """(mode, tiles) of ``light`` from the frame's first plan's (``FrameShare.derived``): each
    sheared to the sun's direction, or moved to the light's position."""
    if light.type == "SUN":
        fits = [None if t is None else lightspace.sheared(t.fit, light.direction) for t in first]
    else:
        offset = light.position - position
        fits = [None if t is None else lightspace.moved(t.fit, offset) for t in first]
    tiles = [None if t is None else Tile(f, t.casters, t.size, held=t.held) for t, f in zip(first, fits, strict=True)]
    return mode, tiles


def _planned_tiles(scene, share, index, light):
    """(mode, tiles) of light ``index`` planned afresh: at its known sizes, or at the largest
    and then again at the sizes density asks for (``ViewFit.density``)."""
    options = scene.options
    world = light.world
    cone = share.cones.get(index, 0.0) if share.cones is not None and light.type == "SUN" and not world else 0.0
    reach = share.reaches.get(index, 0.0) if share.reaches is not None and light.type != "SUN" else 0.0
    job = _Job(light, _flat_free(scene, light), {}, cone, reach, light.sampled or options.pcss)
    known = share.known_sizes.get(index) if share.known_sizes is not None and not world else None
    map_size = options.map_size
    largest = min(map_size, max(1, int(options.world_map_size))) if world and options.world_map_size else map_size
    if world:
        known = [largest] * 6  # a direction of the world is drawn once: one fit, no density pass
    tiles, mode = _light_tiles(scene, job, list(known) if known else [largest] * 6)
    if not known:
        hint = share.hinted_sizes.get(index) if share.hinted_sizes is not None and not world else None
        tiles, mode = _at_density(scene, job, tiles, mode, largest, hint)
    return mode, tiles


# A hinted map size is kept while density asks for at most twice and at least a quarter of it.
SIZE_HYSTERESIS = (0.25, 2.0)


def _hinted(sizes, hint):
    """``sizes`` with each replaced by ``hint``'s where that is within SIZE_HYSTERESIS of it."""
    if not hint:
        return sizes
    lo, hi = SIZE_HYSTERESIS
    return [h if h is not None and lo * h <= s <= hi * h else s for s, h in zip(sizes, list(hint) + [None] * 6)]


def _at_density(scene, job, tiles, mode, largest, hint=None):
    """A map needs no more texels than the pixels it shadows can show (density): each map
    (cascade, cube face) of the light, planned at ``largest``, is planned again at the size
    it needs. A sun fitted to the whole scene (no view corners) keeps its size: it must not
    depend on the camera, so moving the view never redraws it. Returns (tiles, mode)."""
    density, receivers = scene.view.density, scene.receivers
    camera_bound = job.light.type != "SUN" or scene.view.view_corners is not None
    if density is None or receivers is None or not camera_bound or not any(t is not None for t in tiles):
        return tiles, mode
    per_pixel = density.texels_per_pixel * (1.0 if job.soft else max(1.0, scene.options.kernel - 1.0))
    sizes = needed_sizes(tiles, largest, receivers, density, per_pixel)
    sizes = [min(s, largest) for s in _hinted(sizes, hint)]
    if min(sizes, default=largest) < largest:
        smaller, smaller_mode = _light_tiles(scene, job, sizes)
        if [t is None for t in smaller] == [t is None for t in tiles]:
            return smaller, smaller_mode
    return tiles, mode


def _flat_free(scene, light):
    """Flat boxes that shadow nothing under ``light`` (None: not tested)."""
    corners, view_corners = scene.boxes.corners, scene.view.view_corners
    if scene.options.reflective:  # every lit surface sends light: none is left out
        return np.zeros(len(corners), dtype=bool) if light.type == "SUN" and view_corners is not None else None
    if light.type != "SUN":
        return scene.flat.free(position=light.position)
    return None if view_corners is None else scene.flat.free(light.direction)


def _grown(scene, job):
    """The boxes and the crop a local light is planned over: the scene's, or grown by the
    job's reach (see ``FrameShare.reaches``; kept in its ``memo``)."""
    reach, memo = job.reach, job.memo
    if not reach > 0.0 or not math.isfinite(reach):
        return scene.boxes, scene.receivers
    if "grown" not in memo:
        receivers = scene.receivers
        seen = None if receivers is None else lightspace.dilated_receivers(receivers, reach)
        memo["grown"] = (Boxes.of(lightspace.dilated_boxes(scene.boxes.corners, reach)), seen)
    return memo["grown"]


def _light_tiles(scene, job, sizes):
    """The tiles of the job's light (per cascade or cube face: None where it needs no map)
    and their mode; ``sizes[k]``: texels a side of the k-th one."""
    kind = job.light.type
    if kind == "SUN":
        tiles, mode = _sun_tiles(scene, job, sizes)
    elif kind == "SPOT":
        tiles, mode = _spot_tiles(scene, job, sizes)
    else:  # POINT, AREA
        tiles, mode = _cube_tiles(scene, job, sizes)
    for k, t in enumerate(tiles):
        if t is not None:
            t.size = sizes[k]
    return tiles, mode


def _sun_tiles(scene, job, sizes):
    """A sun's map fitted to the whole scene, to the whole view, or one per cascade."""
    light, corners = job.light, scene.boxes.corners
    view_corners, slices = scene.view.view_corners, scene.slices
    count, flat_free = len(corners), job.flat_free
    extra = scene.view.extra
    if extra is not None and len(extra):
        # Receivers that cast nothing: after the geometry's boxes (caster indices stay the
        # draws'), never casters.
        if flat_free is None and view_corners is not None:
            flat_free = scene.flat.free(light.direction)
        corners = np.concatenate([corners, np.asarray(extra, np.float64).reshape(-1, 8, 3)])
        if flat_free is not None:
            flat_free = np.concatenate([flat_free, np.ones(len(corners) - count, dtype=bool)])
    # How far a PCSS penumbra spreads out of a caster's footprint, per unit of depth.
    angle = min(max(light.angle, 0.0), math.pi * 0.99)
    spread = math.tan(0.5 * angle) * light.penumbra_scale if job.soft else 0.0
    if view_corners is None:
        fit = lightspace.fit_sun_ortho(light.direction, corners.reshape(-1, 3), sizes[0])
        tiles = [Tile(fit, np.arange(count))] if fit is not None else []
    elif slices is None or light.world:
        fitted = lightspace.fit_sun_to_view(
            light.direction,
            corners,
            view_corners,
            sizes[0],
            soft=spread,
            flat_free=flat_free,
            parts=scene.parts(),
            cone=job.cone,
            kept=_sun_slot(scene, light, sizes[0], spread, job.cone, 0),
        )
        tiles = [Tile(*fitted)] if fitted is not None else []
    else:
        fits = [
            lightspace.fit_sun_to_view(
                light.direction,
                corners,
                sc,
                sizes[k],
                soft=spread,
                flat_free=flat_free,
                cone=job.cone,
                kept=_sun_slot(scene, light, sizes[k], spread, job.cone, k),
            )
            for k, (sc, _end) in enumerate(slices)
        ]
        tiles = [Tile(*f) if f is not None else None for f in fits]
    cascaded = view_corners is not None and slices is not None and len(slices) > 1 and not light.world
    return tiles, "CASCADE" if cascaded else "SINGLE"


def _sun_slot(scene, light, size, spread, cone, cascade):
    """(``ViewFit.windows``, this sun map's slot in it) while the view moves, else None. The
    world's directions change every frame and keep nothing."""
    windows = scene.view.windows
    if windows is None or light.world:
        return None
    direction = np.asarray(light.direction, np.float64).tobytes()
    return windows, ("sun", direction, int(size), float(spread), float(cone), cascade)


def _spot_tiles(scene, job, sizes):
    """A spot's one perspective map, a little wider than its cone."""
    light = job.light
    fov = min(light.cone_size * 1.05 + 4.0 / max(scene.options.map_size, 1), math.radians(170.0))
    boxes, seen = _grown(scene, job)
    crop = None if seen is None else Crop(seen, job.flat_free, scene.view.windows)
    tile = perspective_tile(Eye(light.position, light.direction, fov), boxes, sizes[0], crop=crop, memo=job.memo)
    return [tile] if tile is not None else [], "SINGLE"


def _cube_tiles(scene, job, sizes):
    """A point or area light's cube faces (None for an area light's face wholly behind it)."""
    light = job.light
    boxes, seen = _grown(scene, job)
    crop = None if seen is None else Crop(seen, job.flat_free, scene.view.windows)
    soft = job.soft
    faces = [
        k
        for k, fwd in enumerate(lightspace.CUBE_FORWARDS)
        if not (light.type == "AREA" and behind_area_light(fwd, light.direction))
    ]
    planned = perspective_tiles(
        [Eye(light.position, lightspace.CUBE_FORWARDS[k], math.pi / 2.0) for k in faces],
        boxes,
        [sizes[k] for k in faces],
        kernel=1.0 if soft else scene.options.kernel,
        soft_radius=light.shadow_radius * light.penumbra_scale if soft else 0.0,
        crop=crop,
        memo=job.memo,
    )
    tiles = [None] * len(lightspace.CUBE_FORWARDS)
    for k, tile in zip(faces, planned, strict=True):
        tiles[k] = tile
    return tiles, "CUBE"


def _add(plan, index, mode, tiles, slices, depth_range):
    """Light ``index``'s ``tiles`` (None where it needs no map) into ``plan``: nothing when it
    has none; counted in ``plan.unshadowed`` when they do not fit in MAX_SHADOW_TILES."""
    if not any(t is not None for t in tiles):
        return  # no caster in reach: no map at all
    needed = sum(t is not None for t in tiles)
    if len(plan.tiles) + needed > MAX_SHADOW_TILES:
        plan.unshadowed += 1
        return
    entry = LightShadow(mode)
    if mode == "CASCADE":
        entry.splits = tuple(end for _sc, end in slices)
        entry.blend = cascade_blend([end for _sc, end in slices], depth_range or ())
    for t in tiles:
        if t is None:
            entry.tiles.append(-1)
        else:
            entry.tiles.append(len(plan.tiles))
            plan.tiles.append(t)
    plan.lights[index] = entry


def frame_tiles(plan, lights, reaches=None):
    """{light index: (mode, its tiles or None per map, its position)} of ``plan`` (a frame's
    first plan, fitted with ``cones`` and ``reaches``): its suns other than the world's
    directions, and the local lights in ``reaches``; what the frame's later samples shear or
    move (``FrameShare.derived``)."""
    reaches = reaches or {}
    return {
        i: (entry.mode, [plan.tiles[t] if t >= 0 else None for t in entry.tiles], lights[i].position)
        for i, entry in plan.lights.items()
        if i < len(lights) and not lights[i].world and (lights[i].type == "SUN" or i in reaches)
    }


def frame_sizes(plan, map_size):
    """{light index: texels a side of each of its maps (``map_size`` where it needs none)} of
    ``plan``: what ``FrameShare.known_sizes`` takes for the frame's later samples."""
    return {
        i: [plan.tiles[t].size if t >= 0 else map_size for t in entry.tiles] + [map_size] * (6 - len(entry.tiles))
        for i, entry in plan.lights.items()
    }


def cascade_slices(corners, view_corners, camera, requested, depth=None):
    """[(slice corners, view depth where the slice ends)] of the visible depth range: one
    slice (the view frustum cut to the depth range of what it sees, so a far clip plane
    beyond the geometry does not widen the map), or one per sun cascade. None when the range
    is unknown (then the whole frustum is fitted). Cascades are widened by CASCADE_OVERLAP of
    their depth on both sides, so filters near a split still read inside a map."""
    if camera is None or view_corners is None:
        return None
    if depth is None:
        depth = lightspace.view_depth_range(camera.projection, camera.view, corners, camera.is_ortho)
    clip = lightspace.clip_range(camera.projection, camera.is_ortho)
    if depth is None or clip is None:
        return None
    count = lightspace.cascade_count(*depth, requested)
    splits = lightspace.cascade_splits(*depth, count)
    out = []
    for a, b in zip(splits[:-1], splits[1:], strict=True):
        pad = CASCADE_OVERLAP * (b - a) if count > 1 else 0.0
        lo, hi = max(a - pad, clip[0]), min(b + pad, clip[1])
        out.append((lightspace.slice_corners(view_corners, clip[0], clip[1], lo, hi), float(b)))
    return out


CASCADE_OVERLAP = 0.1


def cascade_blend(ends, depth_range=()):
    """Per split between cascades, the view depth before it over which the lit pass moves
    from one cascade to the next (dithered, stratified over the frame's samples, so a seam
    becomes a gradual change of texel size): half the overlap both maps cover there, so the
    next map's filter still reads inside it."""
    ends = [float(e) for e in ends]
    if len(ends) < 2:
        return ()
    start = float(depth_range[0]) if len(depth_range) else ends[0] - (ends[1] - ends[0])
    bounds = [start, *ends]
    out = []
    for k in range(len(ends) - 1):
        a, b, c = bounds[k], bounds[k + 1], bounds[k + 2]
        out.append(0.5 * CASCADE_OVERLAP * min(b - a, c - b))
    return tuple(out)


def pack_tiles(sizes):
    """Square maps of ``sizes`` texels a side packed into square slots as wide as the widest:
    (slot width, slot count, per map (slot, x, y) of its lower-left texel in its slot). Widest
    first; each map takes the smallest free cell it fits, and a cell twice as wide as the map
    or more is split in four (a quadtree), so maps of power-of-two sizes leave no gaps."""
    if not sizes:
        return 0, 0, []
    slot = max(int(n) for n in sizes)
    free = []  # (width, slot, x, y)
    count = 0
    where = [None] * len(sizes)
    for i in sorted(range(len(sizes)), key=lambda k: (-int(sizes[k]), k)):
        n = int(sizes[i])
        fits = [c for c in free if c[0] >= n]
        if fits:
            cell = min(fits)
            free.remove(cell)
        else:
            cell = (slot, count, 0, 0)
            count += 1
        width, index, x, y = cell
        while width // 2 >= n:
            width //= 2
            free += [(width, index, x + width, y), (width, index, x, y + width), (width, index, x + width, y + width)]
        where[i] = (index, x, y)
    return slot, count, where
