"""Depth of field by sampling the lens (Haeberli and Akeley 1990, *The Accumulation Buffer*;
Cook, Porter and Carpenter 1984, *Distributed Ray Tracing*): each sample of a frame looks
from its own point of the camera's aperture, with its projection sheared so the plane at the
focus distance projects where the centre of the lens puts it, and the film's average over the
samples converges to a thin lens's image, as Cycles' camera rays from the same aperture.

Numpy only. The lens is Blender's (``extract.Lens``): an aperture of ``radius`` world units, a
disc or a regular polygon of ``blades`` corners turned by ``rotation``, its x divided by
``ratio``; points on it follow Cycles' sampling of the aperture (a uniform disc, or a uniform
polygon with corners at the radius).

A point at view depth z (its distance along the view axis) seen from lens offset o moves on
screen by o (1/f - 1/z) k pixels for a perspective camera (f the focus distance, k the
projection's pixels per unit of x / z), o (z/f - 1) k for an orthographic one (k its pixels
per unit): its circle of confusion is 2 r |1/f - 1/z| k across (``coc_pixels``).
"""

import math

import numpy as np

from .sampling import radical_inverse

# The lens's own low-discrepancy sequence: Halton bases not used by the pixel offsets (2, 3),
# so a sample's point of the lens does not follow its point of the pixel.
LENS_BASES = (5, 7)


def aperture_point(u, v, lens):
    """The point of ``lens``'s aperture (camera-space x, y in world units) for (u, v) in [0, 1)^2:
    a uniform disc through Shirley and Chiu's concentric mapping (strata stay compact), or a
    uniform regular polygon as Cycles samples it (a corner's triangle, then a point in it)."""
    if lens.blades >= 3:
        n = float(lens.blades)
        corner = math.floor(u * n)
        u = u * n - corner
        u = math.sqrt(u)
        v = v * u
        u = 1.0 - u
        half = math.pi / n
        px, py = (u + v) * math.cos(half), (u - v) * math.sin(half)
        turn = lens.rotation + corner * 2.0 * half
        x = math.cos(turn) * px - math.sin(turn) * py
        y = math.sin(turn) * px + math.cos(turn) * py
    else:
        a, b = 2.0 * u - 1.0, 2.0 * v - 1.0
        if a == 0.0 and b == 0.0:
            x = y = 0.0
        elif abs(a) > abs(b):
            x, y = a * math.cos(0.25 * math.pi * b / a), a * math.sin(0.25 * math.pi * b / a)
        else:
            x, y = b * math.sin(0.25 * math.pi * a / b), b * math.cos(0.25 * math.pi * a / b)
    return x * lens.radius / lens.ratio, y * lens.radius


def lens_offset(s, lens):
    """Sample ``s``'s point of the aperture: the centre for sample 0 (the frame's centred
    sample, whose depth and normal are the passes', and the settle pilot's), then the Halton
    points of LENS_BASES (so the frame's samples spread over the whole aperture in order, a
    prefix of them evenly)."""
    if s == 0:
        return 0.0, 0.0
    return aperture_point(radical_inverse(s, LENS_BASES[0]), radical_inverse(s, LENS_BASES[1]), lens)


def lens_camera(camera, offset):
    """``camera`` (an ``extract.Camera`` with a ``lens``) seen from ``offset`` (camera-space x,
    y of its aperture): the eye moved by it, the projection sheared so the focus plane stays
    where the centre of the lens projects it (x' = x - o + o (-z) / f in view space)."""
    ox, oy = float(offset[0]), float(offset[1])
    if ox == 0.0 and oy == 0.0:
        return camera
    f = camera.lens.focus
    move = np.eye(4)
    move[0, 3], move[1, 3] = -ox, -oy
    shear = np.eye(4)
    shear[0, 2], shear[1, 2] = -ox / f, -oy / f
    return type(camera)(
        view=move @ np.asarray(camera.view, np.float64),
        projection=np.asarray(camera.projection, np.float64) @ shear,
        is_ortho=camera.is_ortho,
        lens=camera.lens,
    )


def coc_scale(camera, width, height):
    """(k_x, k_y): the projection's pixels per unit of x / z (perspective) or of x
    (orthographic), and of y, on a ``width`` x ``height`` image."""
    p = np.asarray(camera.projection, np.float64)
    return abs(p[0, 0]) * 0.5 * width, abs(p[1, 1]) * 0.5 * height


def coc_pixels(camera, depth, width, height):
    """The circle of confusion's diameter in pixels (the larger of x and y) at view ``depth``
    (distance along the view axis) for ``camera``'s lens; 0 without one."""
    lens = camera.lens
    if lens is None:
        return 0.0
    kx, ky = coc_scale(camera, width, height)
    k = max(kx / lens.ratio, ky)
    depth = max(float(depth), 1e-30)
    spread = abs(depth / lens.focus - 1.0) if camera.is_ortho else abs(1.0 / lens.focus - 1.0 / depth)
    return 2.0 * lens.radius * spread * k


def lens_reach(camera, depth_range, width, height, cap=None):
    """How many pixels beyond the image the frame's lens samples look: the largest circle of
    confusion's radius over view depths ``depth_range`` (near, far), so shadow maps and light
    bins planned from the centre of the lens hold what every point of it sees; at most ``cap``
    (default: the image's larger side) where a near surface's blur would widen them past use."""
    if camera.lens is None:
        return 0.0
    near, far = (float(d) for d in depth_range)
    cap = float(max(width, height)) if cap is None else float(cap)
    if not (math.isfinite(near) and math.isfinite(far)) or far <= 0.0:
        return cap
    near = max(near, 1e-6 * max(far, 1e-30))
    # |1/f - 1/z| (and |z/f - 1|) is largest at an end of the range.
    reach = 0.5 * max(coc_pixels(camera, near, width, height), coc_pixels(camera, far, width, height))
    return min(reach, cap) if math.isfinite(reach) else cap


def coc_row(camera, width, height):
    """The frame block's ``lens_coc`` (x: the aperture's radius times the pixels per unit,
    the larger of x and y; y: 1 / focus; z: 1 for a lens): what the settle test needs to
    find where the lens blurs more than half a pixel; zeros without a lens."""
    lens = camera.lens
    if lens is None:
        return (0.0, 0.0, 0.0, 0.0)
    kx, ky = coc_scale(camera, width, height)
    return (lens.radius * max(kx / lens.ratio, ky), 1.0 / lens.focus, 1.0, 0.0)
