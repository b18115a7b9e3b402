"""Hair as strips: Curves objects and particle hair -> a ``Geometry`` of strips that the vertex
shaders widen (``shaders/mesh.vert.glsl``, ``shaders/shadow_depth.vert.glsl``).

A strand's points become two vertices each, on its centre line, with the strand's tangent as
their normal and (side, radius) as ``Geometry.strands``: each pass moves them sideways, across
the tangent and facing its own eye (the camera in the lit pass, the light in a shadow map), as
EEVEE does (its curves vertex shader builds the strip toward whatever view draws it). Nothing
here depends on the camera, so the strips are built once per geometry update.

Curves read as Blender stores them (points, curve offsets, the ``radius`` attribute and the
``material_index`` of each curve); Catmull-Rom curves (the hair default) are evaluated at their
``resolution`` as Blender's ``catmull_rom`` does; poly curves are drawn as they are; Bézier and
NURBS curves through their control points (named). Particle hair is read from the evaluated
path cache (``ParticleSystem.co_hair``: the render or viewport steps and child count Blender
evaluated, Simplify's child factor included), its radius from the particle settings' root,
tip, shape and scale, as EEVEE's ``hair_shape_radius``.
"""

import numpy as np

from .geometry import Geometry

DEFAULT_RESOLUTION = 12  # Blender's resolution of a curve without the attribute
CURVE_TYPES = {0: "CATMULL_ROM", 1: "POLY", 2: "BEZIER", 3: "NURBS"}


def catmull_rom(points, offsets, values, resolution):
    """Catmull-Rom curves (``points`` (P, 3), curve c from ``offsets[c]`` to ``offsets[c+1]``)
    evaluated at ``resolution`` (per curve) steps a segment, end points repeated as Blender's
    non-cyclic curves do; ``values`` (P, k) interpolated alike -> (points, offsets, values)."""
    points = np.asarray(points, np.float64)
    values = np.asarray(values, np.float64).reshape(len(points), -1)
    counts = np.diff(offsets)
    resolution = np.maximum(np.broadcast_to(np.asarray(resolution, np.int64), counts.shape), 1)
    out_counts = np.where(counts > 1, (counts - 1) * resolution + 1, counts)
    out_offsets = np.concatenate([[0], np.cumsum(out_counts)]).astype(np.int64)
    total = int(out_offsets[-1])
    # Each evaluated point: its curve, its segment in that curve and its parameter in the segment.
    curve = np.repeat(np.arange(len(counts)), out_counts)
    local = np.arange(total) - out_offsets[curve]
    res = resolution[curve]
    seg = np.minimum(local // res, np.maximum(counts[curve] - 2, 0))
    t = (local - seg * res) / res
    first, last = offsets[:-1][curve], offsets[1:][curve] - 1
    i1 = first + seg
    i0, i2 = np.maximum(i1 - 1, first), np.minimum(i1 + 1, last)
    i3 = np.minimum(i1 + 2, last)
    t2, t3 = t * t, t * t * t
    w = 0.5 * np.stack([-t + 2 * t2 - t3, 2 - 5 * t2 + 3 * t3, t + 4 * t2 - 3 * t3, -t2 + t3], axis=1)
    both = np.concatenate([points, values], axis=1)
    out = sum(w[:, k : k + 1] * both[i] for k, i in enumerate((i0, i1, i2, i3)))
    return out[:, :3], out_offsets, out[:, 3:]


def strips(points, offsets, radii, curve_materials=None):
    """The strip ``Geometry`` of polylines ``points`` (P, 3) split by ``offsets`` (C + 1), with
    a radius per point (``radii``, P) and a material index per curve (``curve_materials``)."""

    points = np.asarray(points, np.float32)
    offsets = np.asarray(offsets, np.int64)
    radii = np.asarray(radii, np.float32).reshape(-1)
    finite = np.isfinite(points).all(axis=1) & np.isfinite(radii)
    radii = np.where(finite, np.maximum(radii, 0.0), 0.0).astype(np.float32)
    points = np.where(finite[:, None], points, 0.0).astype(np.float32)
    n = len(points)
    counts = np.diff(offsets)
    curve_of = np.repeat(np.arange(len(counts)), counts)
    # Segments j -> j + 1 within a curve, both ends finite.
    seg = np.arange(max(n - 1, 0))
    inside = curve_of[:-1] == curve_of[1:] if n > 1 else np.zeros(0, bool)
    seg = seg[inside & finite[:-1] & finite[1:]] if n > 1 else seg
    # Tangents: the sum of the unit directions to the neighbours along the curve.
    d = np.diff(points.astype(np.float64), axis=0)
    length = np.linalg.norm(d, axis=1, keepdims=True)
    unit = np.divide(d, length, out=np.zeros_like(d), where=length > 0.0)
    tangent = np.zeros((n, 3))
    tangent[seg] += unit[seg]
    tangent[seg + 1] += unit[seg]
    vertices = np.repeat(points, 2, axis=0)
    normals = np.repeat(tangent.astype(np.float32), 2, axis=0)
    strands = np.empty((2 * n, 2), np.float32)
    strands[0::2, 0], strands[1::2, 0] = -1.0, 1.0
    strands[:, 1] = np.repeat(radii, 2)
    a = 2 * seg
    tris = np.stack([a, a + 1, a + 2, a + 1, a + 3, a + 2], axis=1).reshape(-1, 3).astype(np.int32)
    mats = np.zeros(len(seg), np.int64) if curve_materials is None else np.asarray(curve_materials)[curve_of[seg]]
    mats = np.repeat(mats, 2)
    ranges = []
    if len(mats):
        order = np.argsort(mats, kind="stable")
        tris, mats = tris[order], mats[order]
        values, starts, sizes = np.unique(mats, return_index=True, return_counts=True)
        ranges = [(int(v), int(s), int(c)) for v, s, c in zip(values, starts, sizes, strict=True)]
    used = np.zeros(n, bool)
    used[seg] = used[seg + 1] = True
    if used.any():
        pad = float(radii[used].max())
        bounds = np.array([points[used].min(axis=0) - pad, points[used].max(axis=0) + pad], np.float64)
    else:
        bounds = np.full((2, 3), np.nan)
    return Geometry(
        np.ascontiguousarray(vertices),
        np.ascontiguousarray(normals),
        np.ascontiguousarray(tris),
        ranges,
        bounds,
        strands=strands,
    )


def _attr(data, name, count, dtype, width=1, prop="value"):
    attr = data.attributes.get(name)
    if attr is None or len(attr.data) != count:
        return None
    out = np.empty(count * width, dtype)
    attr.data.foreach_get(prop, out)
    return out.reshape(-1, width) if width > 1 else out


def geometry_from_curves(curves):
    """The strips of a Curves datablock (Blender's hair curves, evaluated)."""
    n_points, n_curves = len(curves.points), len(curves.curves)
    points = _attr(curves, "position", n_points, np.float32, 3, "vector")
    offsets = np.empty(n_curves + 1, np.int32)
    curves.curve_offset_data.foreach_get("value", offsets)
    radii = _attr(curves, "radius", n_points, np.float32)
    radii = np.full(n_points, 0.01, np.float32) if radii is None else radii  # Blender's default radius
    types = _attr(curves, "curve_type", n_curves, np.int8)
    types = np.zeros(n_curves, np.int8) if types is None else types
    resolution = _attr(curves, "resolution", n_curves, np.int32)
    resolution = np.full(n_curves, DEFAULT_RESOLUTION, np.int32) if resolution is None else resolution
    materials = _attr(curves, "material_index", n_curves, np.int32)
    messages = []
    other = sorted({CURVE_TYPES.get(int(t), str(t)) for t in np.unique(types) if int(t) not in (0, 1)})
    if other:
        messages.append(f"curves '{curves.name}': {', '.join(other)} curves are drawn through their control points")
    if points is None or n_points == 0:
        return strips(np.zeros((0, 3)), np.zeros(1, np.int64), np.zeros(0), None)
    smooth = types == 0
    if smooth.any():
        # Catmull-Rom curves at their resolution; the others (poly, and Bézier or NURBS through
        # their control points) at resolution 1: the same points.
        res = np.where(smooth, resolution, 1)
        points, offsets, radii = catmull_rom(points, offsets.astype(np.int64), radii[:, None], res)
    geo = strips(points, offsets, radii[:, 0] if radii.ndim > 1 else radii, materials)
    geo.messages = tuple(messages)
    return geo


def strand_radius(settings, steps):
    """The radius at each of a strand's ``steps`` + 1 points (root first) of a particle hair
    system with settings ``settings``: EEVEE's ``hair_shape_radius`` of root and tip diameter
    and strand shape, times the radius scale, halved; 0 at the tip with Close Tip."""
    t = np.linspace(0.0, 1.0, steps + 1)
    shape = float(getattr(settings, "shape", 0.0))
    radius = 1.0 - t
    radius = radius ** (1.0 + shape) if shape < 0.0 else radius ** (1.0 / max(1.0 - shape, 1e-6))
    # The settings' "radius" is a diameter (the panel's Diameter Root and Tip): EEVEE halves it.
    root, tip = float(settings.root_radius), float(settings.tip_radius)
    out = (radius * (root - tip) + tip) * float(settings.radius_scale) * 0.5
    if getattr(settings, "use_close_tip", False):
        out[t > 0.99] = 0.0
    return out


def geometry_from_particles(ob, psys, render):
    """The strips of particle hair system ``psys`` of evaluated object ``ob``, in ``ob``'s
    object space. ``render``: the depsgraph evaluates render settings (render steps and
    child count), else viewport ones."""
    settings = psys.settings
    steps = 1 << int(settings.render_step if render else settings.display_step)
    parents, children = len(psys.particles), len(psys.child_particles)
    if children and settings.child_type != "NONE":
        index = list(range(parents, parents + children))
        if getattr(settings, "use_parent_particles", False):
            index = list(range(parents)) + index
    else:
        index = list(range(parents))
    co = np.empty((len(index), steps + 1, 3), np.float64)
    co_hair = psys.co_hair
    for row, i in enumerate(index):
        for k in range(steps + 1):
            co[row, k] = co_hair(object=ob, particle_no=i, step=k)
    inverse = np.linalg.inv(np.array(ob.matrix_world, np.float64))
    points = co.reshape(-1, 3) @ inverse[:3, :3].T + inverse[:3, 3]
    offsets = np.arange(len(index) + 1, dtype=np.int64) * (steps + 1)
    radii = np.tile(strand_radius(settings, steps), len(index))
    return strips(points, offsets, radii, None)


def particle_hair(ob, render):
    """The particle systems of evaluated object ``ob`` drawn as hair: type HAIR, rendered as
    Path, with their particle system modifier enabled for renders (``render``) or the viewport."""
    enabled = {}
    for mod in getattr(ob, "modifiers", ()):
        if mod.type == "PARTICLE_SYSTEM" and mod.particle_system is not None:
            enabled[mod.particle_system.name] = bool(mod.show_render if render else mod.show_viewport)
    out = []
    for psys in getattr(ob, "particle_systems", ()):
        settings = psys.settings
        if settings is None or settings.type != "HAIR" or settings.render_type != "PATH":
            continue
        if enabled.get(psys.name, True):
            out.append(psys)
    return out
