"""Where the world's light gets in: a visibility probe of the sky for rooms without portals.

Inside a room lit through a window, almost every direction of the world is blocked by its
walls: directions drawn over the whole sphere mostly find nothing to add, and the ratio of a
few directions to the sky's SH light (``directions.py``) says little about the light through
the window. Cycles' light portals tell where the light gets in; most interiors users render
have none. This probe finds the openings from depth, once a frame: a small cube of view
depths (six faces of PROBE_TEXELS², the camera depth prepass's program, ``occlusion.py``)
drawn from the centre of the box around what the camera sees. A texel where nothing is drawn
looks at the sky. Where the open texels (weighted by their solid angle and the world's
radiance) hold under INTERIOR_SHARE of the world's light seen from there, the frame is an
interior: its openings (a window, a skylight, a door) are placed at the depth of the walls
around them, and the directions from every surface the probe sees to every point of them make
a guide (``opening_guide``, a distribution over the sphere). The frame then draws its
directions as it does through light portals (``directions.world_lights``: three quarters from
the guide, the rest from the world's own distribution over the whole sphere, each carrying the
world's light over the mixture's probability), so the estimate stays unbiased whatever the
guide misses.

Outdoors (the sky over a fifth of the probe or more) and in a closed box (no opening) the
probe changes nothing; with Cycles' light portals, or where lamps give most of the light
(``probe_due``), it is not drawn. It costs six depth passes of 32² and one read-back of 6 x
32² floats a frame (kept while the draws and the world are the same: the viewport's frames).
"""

import math
from types import SimpleNamespace

import numpy as np

from ...shadows import lightspace
from .directions import frame_towards, guide, light_share, needs_directions

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
# (``directions.light_share``) is not probed: lamps light that frame, whatever comes in.
PROBE_SHARE = 0.25
# The faces: the direction each looks along.
FACES = np.array(
    [[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, -1.0]]
)


def probe_due(snapshot, draws, settings):
    """Whether a frame looks for the world's openings: World > Shadows on, a world that gives
    light (``directions.needs_directions``) and at least PROBE_SHARE of the light at the middle
    of what the camera sees, and no light portal (Cycles' portals say where it gets in)."""
    from ..draw_list import corners_of

    if getattr(snapshot, "portals", ()) or not needs_directions(snapshot.world, settings):
        return False
    seen = [d for d in draws if d.instance.camera]
    if not seen:
        return False
    box = corners_of(seen).reshape(-1, 3)
    centre = 0.5 * (box.min(axis=0) + box.max(axis=0))
    return np.all(np.isfinite(centre)) and light_share(snapshot.world, snapshot.lights, centre) >= PROBE_SHARE


def face_camera(centre, forward, radius):
    """The raster camera of the cube face looking along ``forward`` from world point ``centre``:
    a 90-degree square perspective from 1e-4 to 1e3 times ``radius`` (the box's half diagonal:
    anything of the scene lies well inside). ``rotation``: its camera-to-world rotation (it
    looks along -Z)."""
    rotation = frame_towards(-np.asarray(forward, np.float64))
    view = np.eye(4)
    view[:3, :3] = rotation.T
    view[:3, 3] = -rotation.T @ np.asarray(centre, np.float64)
    near, far = 1e-4 * radius, 1e3 * radius
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


def opening_guide(directions, weights, depths, open_mask, centre, luminance=None):
    """Where the world's light gets into an interior, as a distribution of directions
    (``directions.guide``), or None: the probe's open texels hold nothing, or INTERIOR_SHARE or
    more of the world's light (not an interior), or no wall was seen. ``directions``: (n, 3)
    texel directions; ``weights``: their solid angle x luminance; ``depths``: the distance to
    what each texel shows (0 where open); ``open_mask``: nothing drawn there; ``luminance``:
    the world's luminance towards (m, 3) directions (None: uniform).

    The open texels are grouped into openings (greedily, the brightest first, within
    OPENING_ANGLE of a group's mean: a window, a skylight, a door), each placed at the depth
    of the walls around it (``_wall``). The guide holds the directions from every surface the
    probe sees (its closed texels' points, standing in for what the camera sees inside) to
    every point of every opening, binned on a GUIDE_CELLS equirectangular grid weighted by the
    world's luminance and widened by a cell: the directions that can bring the world's light
    to a surface inside, whatever its distance from the probe."""
    weights = np.asarray(weights, np.float64)
    total = float(weights.sum())
    open_weight = float(weights[open_mask].sum())
    closed = (~open_mask) & (depths > 0.0)
    if not (total > 0.0) or not (open_weight > 0.0) or open_weight >= INTERIOR_SHARE * total or not closed.any():
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
    rays /= np.maximum(np.linalg.norm(rays, axis=1), 1e-300)[:, None]
    ray_weights = np.ones(len(rays)) if luminance is None else np.maximum(luminance(rays), 0.0)
    h, w = GUIDE_CELLS
    u = 0.5 - np.arctan2(rays[:, 1], rays[:, 0]) / (2.0 * math.pi)
    v = np.arctan2(rays[:, 2], np.hypot(rays[:, 0], rays[:, 1])) / math.pi + 0.5
    r = np.clip((v * h).astype(np.int64), 0, h - 1)
    c = np.clip((u * w).astype(np.int64), 0, w - 1)
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

    def cones(self, draws, world, origin, shaders, materials, textures, stats):
        """The frame's ``cones`` (``FramePlan.cones``, as light portals give them): [the guide of
        the openings (``opening_guide``)] of the interior ``draws`` (those the camera sees)
        stand in, or [] outdoors, in a closed box or with nothing drawn. ``world``: the
        snapshot's ``materials.World`` (its radiance weighs the directions). The six faces are
        drawn and read back one after the other (a sync each)."""
        from ..draw_list import corners_of
        from ..film import texture_array
        from .directions import distribution

        seen = [d for d in draws if d.instance.camera and d.instance.hair is None]
        if not seen or world is None:
            return []
        corners = corners_of(seen).reshape(-1, 3)
        lo, hi = corners.min(axis=0), corners.max(axis=0)
        if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))):
            return []
        key = (
            tuple(np.round(lo, 9)),
            tuple(np.round(hi, 9)),
            tuple((id(d.whole), tuple(np.round(np.asarray(d.model).ravel(), 9))) for d in seen),
            np.asarray(world.sh, np.float64).tobytes(),  # the world by content: a frame's is a new object
            id(getattr(world, "env", None)),
        )
        if self._last is not None and self._last[0] == key:
            return self._last[1]
        centre = 0.5 * (lo + hi)
        radius = max(0.5 * float(np.linalg.norm(hi - lo)), 1e-30)
        dist = distribution(world)
        dirs, weights, opened, depths = [], [], [], []
        size = (PROBE_TEXELS, PROBE_TEXELS)
        scratch = SimpleNamespace(ao_draws=0, ao_prepasses=0)  # the AO's counters stay the AO's
        for forward in FACES:
            camera = face_camera(centre, forward, radius)
            self.depth.draw(seen, camera, size, origin, shaders, materials, textures, scratch)
            d, solid = texel_directions(camera.rotation)
            # The view depth along the face's axis, as the distance along each texel's direction.
            depth = texture_array(self.depth.texture, 1)[..., 0] / np.maximum(d @ forward, 1e-6)
            lum = dist.radiance(d.reshape(-1, 3)) @ LUMINANCE
            dirs.append(d.reshape(-1, 3))
            weights.append(solid.ravel() * np.maximum(lum, 0.0))
            opened.append((depth <= 0.0).ravel())
            depths.append(depth.ravel())
        self.depth.release()
        self.drawn += 1
        stats.probe_draws += scratch.ao_draws
        dirs, weights, opened, depths = map(np.concatenate, (dirs, weights, opened, depths))
        lum = lambda d: dist.radiance(d) @ LUMINANCE  # noqa: E731
        found = opening_guide(dirs, weights, depths, opened, centre, lum if dist.env is not None else None)
        result = [found] if found is not None else []
        self._last = (key, result)
        return result

    def release(self):
        self.depth.release()
