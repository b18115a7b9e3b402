"""Where the world's light gets in: a visibility probe of the sky for rooms without portals.

Inside a room lit through a window, almost every direction of the world is blocked by its
walls: directions drawn over the whole sphere mostly find nothing to add, and the ratio of a
few directions to the sky's SH light (``directions.py``) says little about the light through
the window. Cycles' light portals tell where the light gets in; most interiors users render
have none. This probe finds the openings from depth, once a frame: small cubes of view depths
(six faces of PROBE_TEXELS², the camera depth prepass's program, ``occlusion.py``) drawn from
the camera's position, which lies in free space on the side of the walls the camera sees,
and from the middle of what it sees (``opening_guide`` says which decides what). A texel
where nothing is drawn looks at the sky. Where the camera's open texels (weighted by their
solid angle and the world's radiance) hold under INTERIOR_SHARE of the world's light seen from
there, the frame is an interior: the openings (a window, a skylight, a door) are placed at the
depth of the walls around them, and the directions from every surface a probe sees to every
point of them make a guide (``opening_guide``, a distribution over the sphere). The frame
then draws its directions as it does through light portals (``directions.world_lights``:
three quarters from the guide, the rest from the world's own distribution over the whole
sphere, each carrying the world's light over the mixture's probability), so the estimate
stays unbiased whatever the guide misses.

Outdoors (the sky over a fifth of the probe or more) and in a closed box (no opening) the
probe changes nothing; with Cycles' light portals, or where lamps give most of the light
(``PROBE_SHARE``), it is not drawn. It costs twelve depth passes of 32² and their read-backs
(6 x 32² floats each) a frame, kept while the camera, the draws and the world are the same.
"""

import math
from types import SimpleNamespace

import numpy as np

from ...shadows import lightspace
from .directions import equirect_cell, frame_towards, guide

LUMINANCE = np.array([0.2126, 0.7152, 0.0722])

PROBE_TEXELS = 32  # per cube face side
# Below this share of the world's light (at the probe) open to the sky, a frame is an interior.
INTERIOR_SHARE = 0.2
# Openings: open texels within this angle of a group's mean make one (``opening_guide``); at
# most this many, each holding at least this share of the open light.
OPENING_ANGLE = math.radians(60.0)
MAX_OPENINGS = 4
OPENING_MIN_SHARE = 0.02
# The guide: directions from up to GUIDE_SURFACE_POINTS surfaces to up to GUIDE_OPENING_POINTS
# points of each opening, on a grid of GUIDE_CELLS (rows, columns) over the sphere.
GUIDE_SURFACE_POINTS = 400
GUIDE_OPENING_POINTS = 120
GUIDE_CELLS = (32, 64)
# A world that gives less than this share of the unshadowed light at the middle of the view
# (``directions.light_share``) is not probed (``Renderer._world_directions``): lamps light that
# frame, whatever comes in. Nor is a frame with light portals.
PROBE_SHARE = 0.25
# The faces: the direction each looks along.
FACES = np.array(
    [[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, -1.0]]
)


def face_camera(centre, forward, radius):
    """The raster camera of the cube face looking along ``forward`` from world point ``centre``:
    a 90-degree square perspective from 1e-6 to 1e3 times ``radius`` (the farthest anything
    drawn can lie from ``centre``: a room's wall a few centimetres from the camera is drawn
    though a 10 km ground lies outside its window; only coverage and rough distances are read,
    so the depth buffer's precision over that range does not matter). ``rotation``: its
    camera-to-world rotation (it looks along -Z)."""
    rotation = frame_towards(-np.asarray(forward, np.float64))
    view = np.eye(4)
    view[:3, :3] = rotation.T
    view[:3, 3] = -rotation.T @ np.asarray(centre, np.float64)
    near, far = 1e-6 * radius, 1e3 * radius
    return SimpleNamespace(
        view=view, projection=lightspace.perspective(0.5 * math.pi, 1.0, near, far), rotation=rotation
    )


def texel_directions(rotation, texels=PROBE_TEXELS):
    """Unit world directions (texels, texels, 3) of a face's texel centres (row 0 at the
    bottom, as the face's texture reads back) and their solid angles (texels, texels)."""
    c = (np.arange(texels) + 0.5) / texels * 2.0 - 1.0
    x, y = np.meshgrid(c, c)
    v = np.stack([x, y, -np.ones_like(x)], axis=-1)
    length = np.linalg.norm(v, axis=-1)
    d = (v / length[..., None]) @ rotation.T
    solid = (2.0 / texels) ** 2 / length**3
    return d, solid


def is_interior(weights, depths, open_mask):
    """Whether a probe (per texel: ``weights`` solid angle x luminance, ``depths`` the distance
    to what it shows, ``open_mask`` nothing drawn there) stands in an interior: some texels
    open, holding under INTERIOR_SHARE of the world's light, and some wall seen."""
    weights = np.asarray(weights, np.float64)
    total = float(weights.sum())
    open_weight = float(weights[open_mask].sum())
    seen = bool(np.any((~open_mask) & (depths > 0.0)))
    return total > 0.0 and 0.0 < open_weight < INTERIOR_SHARE * total and seen


def probe_rays(directions, weights, depths, open_mask, centre):
    """The directions (n, 3) from every surface one probe at ``centre`` sees to every point of
    the openings it sees, or None where it sees none. The open texels are grouped into openings
    (greedily, the brightest first, within OPENING_ANGLE of a group's mean: a window, a
    skylight, a door), each placed at the depth of the walls around it (``_wall``); the
    surfaces are its closed texels' points, standing in for what the camera sees inside."""
    weights = np.asarray(weights, np.float64)
    closed = (~open_mask) & (depths > 0.0)
    open_weight = float(weights[open_mask].sum())
    if not (open_weight > 0.0) or not closed.any():
        return None
    centre = np.asarray(centre, np.float64)
    cos_group = math.cos(OPENING_ANGLE)
    left = np.nonzero(open_mask & (weights > 0.0))[0]
    points = []
    while left.size and len(points) < MAX_OPENINGS:
        seed = directions[left[np.argmax(weights[left])]]
        group = left[directions[left] @ seed >= cos_group]
        mean = (directions[group] * weights[group][:, None]).sum(axis=0)
        mean /= max(float(np.linalg.norm(mean)), 1e-300)
        regrouped = left[directions[left] @ mean >= cos_group]  # once more, around the group's mean
        group = regrouped if regrouped.size else group
        left = np.setdiff1d(left, group, assume_unique=True)
        if weights[group].sum() < OPENING_MIN_SHARE * open_weight:
            continue
        wall = _wall(directions, depths, closed, directions[group], mean)
        d = directions[group]
        points.append(centre + d[:: max(1, len(d) // GUIDE_OPENING_POINTS)] * wall)
    if not points:
        return None
    opening = np.concatenate(points)
    idx = np.nonzero(closed)[0]
    idx = idx[:: max(1, len(idx) // GUIDE_SURFACE_POINTS)]
    surfaces = centre + directions[idx] * depths[idx][:, None]
    rays = (opening[None, :, :] - surfaces[:, None, :]).reshape(-1, 3)
    return rays / np.maximum(np.linalg.norm(rays, axis=1), 1e-300)[:, None]


def opening_guide(probes, luminance=None):
    """Where the world's light gets into an interior, as a distribution of directions
    (``directions.guide``), or None. ``probes``: [(directions, weights, depths, open_mask,
    centre)] of each probe, the first at the camera; ``luminance``: the world's luminance
    towards (m, 3) directions (None: uniform). The frame is an interior where the first probe
    says so (``is_interior``); the guide then holds the rays (``probe_rays``) of the last probe
    that stands in an interior too (one in the open would add the sky's every direction), binned
    on a GUIDE_CELLS equirectangular grid weighted by the world's luminance and widened by a
    cell: the directions that can bring the world's light to a surface inside, whatever its
    distance from the probe."""
    if not probes or not is_interior(*probes[0][1:4]):
        return None
    # The rays of the last probe that stands in an interior: the middle of the view's sees more
    # of the room than a camera in its corner (measured: 0.018 against 0.033 in the window
    # room; both together 0.023, the corner's rays diluting the middle's).
    rays = next((r for p in reversed(probes) if is_interior(*p[1:4]) for r in [probe_rays(*p)] if r is not None), None)
    if rays is None:
        return None
    ray_weights = np.ones(len(rays)) if luminance is None else np.maximum(luminance(rays), 0.0)
    h, w = GUIDE_CELLS
    r, c = equirect_cell(rays, h, w)
    hist = np.zeros((h, w))
    np.add.at(hist, (r, c), ray_weights)
    # Widened by a cell each way (around the sphere in longitude), at the cell's own weight
    # where it has one: the texels' and the walls' depth are a few degrees off.
    padded = np.pad(hist, ((1, 1), (0, 0)), mode="edge")
    wide = np.max([np.roll(padded, k, axis=1)[1 + j : 1 + j + h] for j in (-1, 0, 1) for k in (-1, 0, 1)], axis=0)
    hist = np.where(hist > 0.0, hist, 0.25 * wide)
    return guide(hist)


def _wall(directions, depths, closed, group_directions, mean):
    """The distance of the walls around an opening (its texels' ``group_directions`` around
    ``mean``): the median distance of the closed texels within its angle of its mean and
    three texels more (a window's frame), else of the nearest few."""
    texel = math.atan(math.sqrt(2.0) / PROBE_TEXELS)
    spread = math.acos(float(np.clip(group_directions @ mean, -1.0, 1.0).min()))
    cos_closed = np.clip(directions[closed] @ mean, -1.0, 1.0)
    ring = cos_closed >= math.cos(min(spread + 3.0 * texel, math.pi))
    if not ring.any():
        ring = cos_closed >= np.sort(cos_closed)[-min(8, cos_closed.size)]
    return float(np.median(depths[closed][ring]))


class WorldProbe:
    """The probe of one renderer: its cube of depth targets (``occlusion.WorldAO`` at
    PROBE_TEXELS² per face) and the last frame's answer, kept while what it was drawn from is
    the same."""

    def __init__(self, pool=None):
        from .occlusion import WorldAO

        self.depth = WorldAO(pool)
        self._last = None  # (key, cones) of the last probe
        self.drawn = 0  # probes drawn since creation (tests read it)

    def cones(self, draws, world, eye, origin, caches, stats):
        """The frame's ``cones`` (``FramePlan.cones``, as light portals give them): [the guide of
        the openings (``opening_guide``)] of the interior ``draws`` (those the camera sees)
        stand in, or [] outdoors, in a closed box or with nothing drawn. ``world``: the
        snapshot's ``materials.World`` (its radiance weighs the directions); ``eye``: the
        camera's position, where the first probe looks from (the middle of the visible box
        where it is not finite); the second looks from that middle; ``caches``: the renderer's
        ``GpuCaches``. Each probe's six faces are drawn and read back one after the other (a
        sync each)."""
        from ..draw_list import corners_of
        from .directions import distribution

        seen = [d for d in draws if d.instance.camera and d.instance.hair is None]
        if not seen or world is None:
            return []
        corners = corners_of(seen).reshape(-1, 3)
        lo, hi = corners.min(axis=0), corners.max(axis=0)
        if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))):
            return []
        eye = np.asarray(eye, np.float64)
        centre = eye if np.all(np.isfinite(eye)) else 0.5 * (lo + hi)
        # The camera's position to a twentieth of the view's box: a viewport's moving camera
        # probes again as it crosses the room, not at every frame (any guide keeps the frame
        # unbiased; it only aims the directions).
        step = 0.05 * max(float(np.linalg.norm(hi - lo)), 1e-30)
        key = (
            tuple(np.round(centre / step)),
            tuple(np.round(lo, 9)),
            tuple(np.round(hi, 9)),
            tuple((id(d.whole), tuple(np.round(np.asarray(d.model).ravel(), 9))) for d in seen),
            np.asarray(world.sh, np.float64).tobytes(),  # the world by content: a frame's is a new object
            id(getattr(world, "env", None)),
        )
        if self._last is not None and self._last[0] == key:
            return self._last[1]
        middle = 0.5 * (lo + hi)
        dist = distribution(world)
        scratch = SimpleNamespace(ao_draws=0, ao_prepasses=0)  # the AO's counters stay the AO's
        probes = []
        # From the camera (the frame is an interior if it stands in one), and from the middle
        # of what it sees (more of the room's openings and surfaces, where that is inside too).
        for point in (
            (centre, middle) if np.linalg.norm(middle - centre) > 1e-6 * (1.0 + np.linalg.norm(hi - lo)) else (centre,)
        ):
            probes.append(self._probe(seen, point, lo, hi, dist, origin, caches, scratch))
        self.depth.release()
        self.drawn += 1
        stats.probe_draws += scratch.ao_draws
        lum = lambda d: dist.radiance(d) @ LUMINANCE  # noqa: E731
        found = opening_guide(probes, lum if dist.env is not None else None)
        result = [found] if found is not None else []
        self._last = (key, result)
        return result

    def _probe(self, seen, centre, lo, hi, dist, origin, caches, stats):
        """One probe at world point ``centre``: (directions, weights, depths, open, centre) of
        its six faces' texels (``opening_guide``'s probes)."""
        from ..film import texture_array

        # Everything drawn lies within this of the probe (the far plane is a thousand times it).
        radius = max(0.5 * float(np.linalg.norm(hi - lo)) + float(np.linalg.norm(centre - 0.5 * (lo + hi))), 1e-30)
        dirs, weights, opened, depths = [], [], [], []
        size = (PROBE_TEXELS, PROBE_TEXELS)
        for forward in FACES:
            camera = face_camera(centre, forward, radius)
            self.depth.draw(seen, camera, size, origin, caches, stats)
            d, solid = texel_directions(camera.rotation)
            # The view depth along the face's axis, as the distance along each texel's direction.
            depth = texture_array(self.depth.texture, 1)[..., 0] / np.maximum(d @ forward, 1e-6)
            lum = dist.radiance(d.reshape(-1, 3)) @ LUMINANCE
            dirs.append(d.reshape(-1, 3))
            weights.append(solid.ravel() * np.maximum(lum, 0.0))
            opened.append((depth <= 0.0).ravel())
            depths.append(depth.ravel())
        return (*map(np.concatenate, (dirs, weights, depths, opened)), centre)

    def release(self):
        self.depth.release()
