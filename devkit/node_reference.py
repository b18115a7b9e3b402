"""numpy twins of the shader-node GLSL functions (``shaders/nodes/*.glsl``), elementwise over
arrays: the tests evaluate them at each pixel's analytic inputs and compare with what the
compiled tree drew. Written from Blender's definitions (the manual's node pages), in float64.
Colours are (..., 4) arrays, vectors (..., 3).
"""

import numpy as np

LUMINANCE = np.array([0.2126, 0.7152, 0.0722])


def _f(x):
    return np.asarray(x, dtype=np.float64)


def safe_divide(a, b):
    a, b = np.broadcast_arrays(_f(a), _f(b))
    out = np.zeros_like(a)
    np.divide(a, b, out=out, where=b != 0.0)
    return out


def compatible_pow(x, y):
    x, y = np.broadcast_arrays(_f(x), _f(y))
    with np.errstate(all="ignore"):
        m = np.mod(-y, 2.0)
        neg = np.where(m == 0.0, np.abs(x) ** y, np.where(m == 1.0, -(np.abs(x) ** y), 0.0))
        pos = np.where(x == 0.0, 0.0, np.abs(x) ** y)
        out = np.where(x < 0.0, neg, pos)
    return np.where(y == 0.0, 1.0, out)


def math_power(a, b):
    a, b = np.broadcast_arrays(_f(a), _f(b))
    f = np.mod(np.abs(b), 1.0)
    whole = (f > 0.999) | (f < 0.001)
    return np.where(a >= 0.0, compatible_pow(a, b), np.where(whole, compatible_pow(a, np.floor(b + 0.5)), 0.0))


def _wrap(a, b, c):
    r = b - c
    with np.errstate(all="ignore"):
        return np.where(r != 0.0, a - r * np.floor(safe_divide(a - c, r)), c)


def _fmod(a, b):
    return np.where(b != 0.0, a - b * np.trunc(safe_divide(a, b)), 0.0)


def _smoothmin(a, b, c):
    with np.errstate(all="ignore"):
        h = np.maximum(c - np.abs(a - b), 0.0) / np.where(c != 0.0, c, 1.0)
    return np.where(c != 0.0, np.minimum(a, b) - h * h * h * c / 6.0, np.minimum(a, b))


def math(op, a, b=0.0, c=0.0, clamp=False):
    """The Math node's operation ``op`` (Blender's identifier, e.g. 'MULTIPLY_ADD')."""
    a, b, c = np.broadcast_arrays(_f(a), _f(b), _f(c))
    with np.errstate(all="ignore"):
        table = {
            "ADD": lambda: a + b,
            "SUBTRACT": lambda: a - b,
            "MULTIPLY": lambda: a * b,
            "DIVIDE": lambda: safe_divide(a, b),
            "MULTIPLY_ADD": lambda: a * b + c,
            "POWER": lambda: math_power(a, b),
            "LOGARITHM": lambda: np.where((a > 0) & (b > 0), np.log(np.abs(a)) / np.log(np.abs(b)), 0.0),
            "SQRT": lambda: np.where(a > 0, np.sqrt(np.abs(a)), 0.0),
            "INVERSE_SQRT": lambda: np.where(a > 0, 1.0 / np.sqrt(np.abs(a)), 0.0),
            "ABSOLUTE": lambda: np.abs(a),
            "EXPONENT": lambda: np.exp(a),
            "MINIMUM": lambda: np.minimum(a, b),
            "MAXIMUM": lambda: np.maximum(a, b),
            "LESS_THAN": lambda: (a < b).astype(float),
            "GREATER_THAN": lambda: (a > b).astype(float),
            "SIGN": lambda: np.sign(a),
            "COMPARE": lambda: (np.abs(a - b) <= np.maximum(c, 1e-5)).astype(float),
            "SMOOTH_MIN": lambda: _smoothmin(a, b, c),
            "SMOOTH_MAX": lambda: -_smoothmin(-a, -b, c),
            "ROUND": lambda: np.floor(a + 0.5),
            "FLOOR": lambda: np.floor(a),
            "CEIL": lambda: np.ceil(a),
            "TRUNC": lambda: np.trunc(a),
            "FRACT": lambda: a - np.floor(a),
            "MODULO": lambda: _fmod(a, b),
            "FLOORED_MODULO": lambda: np.where(b != 0, a - np.floor(safe_divide(a, b)) * b, 0.0),
            "WRAP": lambda: _wrap(a, b, c),
            "SNAP": lambda: np.floor(safe_divide(a, b)) * b,
            "PINGPONG": lambda: np.where(b != 0, np.abs(np.mod(safe_divide(a - b, b * 2.0), 1.0) * b * 2.0 - b), 0.0),
            "SINE": lambda: np.sin(a),
            "COSINE": lambda: np.cos(a),
            "TANGENT": lambda: np.tan(a),
            "ARCSINE": lambda: np.where(np.abs(a) <= 1, np.arcsin(np.clip(a, -1, 1)), 0.0),
            "ARCCOSINE": lambda: np.where(np.abs(a) <= 1, np.arccos(np.clip(a, -1, 1)), 0.0),
            "ARCTANGENT": lambda: np.arctan(a),
            "ARCTAN2": lambda: np.arctan2(a, b),
            "SINH": lambda: np.sinh(a),
            "COSH": lambda: np.cosh(a),
            "TANH": lambda: np.tanh(a),
            "RADIANS": lambda: np.radians(a),
            "DEGREES": lambda: np.degrees(a),
        }
        out = table[op]()
    return np.clip(out, 0.0, 1.0) if clamp else out


def safe_normalize(v):
    v = _f(v)
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    return np.where((n != 0) & np.isfinite(n), v / np.where(n != 0, n, 1.0), 0.0)


def vector_math(op, a, b=0.0, c=0.0, scale=1.0):
    """The Vector Math node: (vector, value)."""
    a, b, c = (
        np.broadcast_to(_f(x), np.broadcast_shapes(np.shape(a), np.shape(b), np.shape(c), (3,))) for x in (a, b, c)
    )
    s = _f(scale)
    zero_v = np.zeros_like(a)
    zero_f = np.zeros(a.shape[:-1])
    dot = lambda x, y: np.sum(x * y, axis=-1)  # noqa: E731
    with np.errstate(all="ignore"):
        if op == "DOT_PRODUCT":
            return zero_v, dot(a, b)
        if op == "DISTANCE":
            return zero_v, np.linalg.norm(a - b, axis=-1)
        if op == "LENGTH":
            return zero_v, np.linalg.norm(a, axis=-1)
        if op == "PROJECT":
            l2 = dot(b, b)[..., None]
            v = np.where(l2 != 0, b * dot(a, b)[..., None] / np.where(l2 != 0, l2, 1), 0.0)
        elif op == "REFLECT":
            n = safe_normalize(b)
            v = a - 2.0 * dot(n, a)[..., None] * n
        elif op == "REFRACT":
            n = safe_normalize(b)
            eta = s[..., None] if np.ndim(s) else s
            d = dot(n, a)[..., None]
            k = 1.0 - eta * eta * (1.0 - d * d)
            v = np.where(k < 0, 0.0, eta * a - (eta * d + np.sqrt(np.maximum(k, 0))) * n)
        elif op == "FACEFORWARD":
            v = np.where((dot(c, b) < 0)[..., None], a, -a)
        else:
            table = {
                "ADD": lambda: a + b,
                "SUBTRACT": lambda: a - b,
                "MULTIPLY": lambda: a * b,
                "DIVIDE": lambda: safe_divide(a, b),
                "MULTIPLY_ADD": lambda: a * b + c,
                "CROSS_PRODUCT": lambda: np.cross(a, b),
                "SCALE": lambda: a * (s[..., None] if np.ndim(s) else s),
                "NORMALIZE": lambda: safe_normalize(a),
                "ABSOLUTE": lambda: np.abs(a),
                "POWER": lambda: math_power(a, b),
                "SIGN": lambda: np.sign(a),
                "MINIMUM": lambda: np.minimum(a, b),
                "MAXIMUM": lambda: np.maximum(a, b),
                "FLOOR": lambda: np.floor(a),
                "CEIL": lambda: np.ceil(a),
                "FRACTION": lambda: a - np.floor(a),
                "MODULO": lambda: _fmod(a, b),
                "WRAP": lambda: _wrap(a, b, c),
                "SNAP": lambda: np.floor(safe_divide(a, b)) * b,
                "SINE": lambda: np.sin(a),
                "COSINE": lambda: np.cos(a),
                "TANGENT": lambda: np.tan(a),
            }
            v = table[op]()
    return v, zero_f


# --- colour ---------------------------------------------------------------------------------


def rgb_to_hsv(c):
    c = _f(c)
    r, g, b = c[..., 0], c[..., 1], c[..., 2]
    cmax = np.maximum(r, np.maximum(g, b))
    cmin = np.minimum(r, np.minimum(g, b))
    d = cmax - cmin
    s = np.where(cmax != 0, d / np.where(cmax != 0, cmax, 1), 0.0)
    dd = np.where(d != 0, d, 1.0)
    cr, cg, cb = (cmax - r) / dd, (cmax - g) / dd, (cmax - b) / dd
    h = np.where(r == cmax, cb - cg, np.where(g == cmax, 2.0 + cr - cb, 4.0 + cg - cr)) / 6.0
    h = np.where(h < 0, h + 1.0, h)
    h = np.where(s != 0, h, 0.0)
    return np.stack([h, s, cmax, c[..., 3]], axis=-1)


def hsv_to_rgb(c):
    c = _f(c)
    h, s, v = c[..., 0], c[..., 1], c[..., 2]
    h = np.where(h == 1.0, 0.0, h) * 6.0
    i = np.floor(h)
    f = h - i
    p, q, t = v * (1 - s), v * (1 - s * f), v * (1 - s * (1 - f))
    choices = [np.stack(x, -1) for x in ((v, t, p), (q, v, p), (p, v, t), (p, q, v), (t, p, v), (v, p, q))]
    rgb = choices[5]
    for k in range(4, -1, -1):
        rgb = np.where((i == k)[..., None], choices[k], rgb)
    rgb = np.where((s == 0)[..., None], np.stack([v, v, v], -1), rgb)
    return np.concatenate([rgb, c[..., 3:4]], axis=-1)


def rgb_to_hsl(c):
    c = _f(c)
    r, g, b = c[..., 0], c[..., 1], c[..., 2]
    cmax = np.maximum(r, np.maximum(g, b))
    cmin = np.minimum(r, np.minimum(g, b))
    ll = np.minimum(1.0, (cmax + cmin) / 2.0)
    d = cmax - cmin
    dd = np.where(d != 0, d, 1.0)
    with np.errstate(all="ignore"):
        s = np.where(ll > 0.5, d / (2.0 - cmax - cmin), d / (cmax + cmin))
    h = np.where(
        cmax == r, (g - b) / dd + np.where(g < b, 6.0, 0.0), np.where(cmax == g, (b - r) / dd + 2.0, (r - g) / dd + 4.0)
    )
    same = cmax == cmin
    return np.stack([np.where(same, 0.0, h / 6.0), np.where(same, 0.0, s), ll, c[..., 3]], axis=-1)


def hsl_to_rgb(c):
    c = _f(c)
    h, s, ll = c[..., 0], c[..., 1], c[..., 2]
    n = np.clip(np.stack([np.abs(h * 6 - 3) - 1, 2 - np.abs(h * 6 - 2), 2 - np.abs(h * 6 - 4)], -1), 0, 1)
    chroma = ((1 - np.abs(2 * ll - 1)) * s)[..., None]
    return np.concatenate([(n - 0.5) * chroma + ll[..., None], c[..., 3:4]], axis=-1)


def _dodge(a, b, f):
    t = 1.0 - f * b
    with np.errstate(all="ignore"):
        return np.where(a == 0, 0.0, np.where(t <= 0, 1.0, np.minimum(a / np.where(t <= 0, 1, t), 1.0)))


def _burn(a, b, f):
    t = (1.0 - f) + f * b
    with np.errstate(all="ignore"):
        return np.where(t <= 0, 0.0, np.clip(1.0 - (1.0 - a) / np.where(t <= 0, 1, t), 0.0, 1.0))


def mix_color(mode, f, a, b, clamp_result=False):
    """The Mix node (Color) with blend ``mode`` (Blender's identifier); A's alpha is kept."""
    a, b = _f(a), _f(b)
    f = _f(f)[..., None] if np.ndim(f) else _f(f)
    x, y = a[..., :3], b[..., :3]
    fm = 1.0 - f
    if mode in {"HUE", "SATURATION", "VALUE", "COLOR"}:
        ha, hb = rgb_to_hsv(a), rgb_to_hsv(b)
        if mode == "HUE":
            h = ha.copy()
            h[..., 0] = hb[..., 0]
            r = np.where(hb[..., 1:2] != 0, x + f * (hsv_to_rgb(h)[..., :3] - x), x)
        elif mode == "COLOR":
            h = ha.copy()
            h[..., :2] = hb[..., :2]
            r = np.where(hb[..., 1:2] != 0, x + f * (hsv_to_rgb(h)[..., :3] - x), x)
        elif mode == "SATURATION":
            h = ha.copy()
            h[..., 1] = (fm * ha[..., 1:2] + f * hb[..., 1:2])[..., 0]
            r = np.where(ha[..., 1:2] != 0, hsv_to_rgb(h)[..., :3], x)
        else:
            h = ha.copy()
            h[..., 2] = (fm * ha[..., 2:3] + f * hb[..., 2:3])[..., 0]
            r = hsv_to_rgb(h)[..., :3]
    else:
        with np.errstate(all="ignore"):
            table = {
                "MIX": lambda: x + f * (y - x),
                "DARKEN": lambda: x + f * (np.minimum(x, y) - x),
                "MULTIPLY": lambda: x + f * (x * y - x),
                "BURN": lambda: _burn(x, y, f),
                "LIGHTEN": lambda: x + f * (np.maximum(x, y) - x),
                "SCREEN": lambda: 1.0 - (fm + f * (1.0 - y)) * (1.0 - x),
                "DODGE": lambda: _dodge(x, y, f),
                "ADD": lambda: x + f * y,
                "OVERLAY": lambda: np.where(x < 0.5, x * (fm + 2 * f * y), 1 - (fm + 2 * f * (1 - y)) * (1 - x)),
                "SOFT_LIGHT": lambda: fm * x + f * ((1 - x) * y * x + x * (1 - (1 - y) * (1 - x))),
                "LINEAR_LIGHT": lambda: x + f * (2.0 * (y - 0.5)),
                "DIFFERENCE": lambda: x + f * (np.abs(x - y) - x),
                "EXCLUSION": lambda: np.maximum(x + f * (y - 2 * x * y), 0.0),
                "SUBTRACT": lambda: x - f * y,
                "DIVIDE": lambda: fm * x + f * safe_divide(x, y),
            }
            r = table[mode]()
    if clamp_result:
        r = np.clip(r, 0.0, 1.0)
    return np.concatenate([r, a[..., 3:4] * np.ones_like(r[..., :1])], axis=-1)


def hue_saturation(hue, sat, value, f, c):
    h = rgb_to_hsv(c)
    h[..., 0] = np.mod(h[..., 0] + hue + 0.5, 1.0)
    h[..., 1] = np.clip(h[..., 1] * sat, 0.0, 1.0)
    h[..., 2] = h[..., 2] * value
    f = _f(f)[..., None] if np.ndim(f) else f
    return c + f * (hsv_to_rgb(h) - c)


def invert(f, c):
    c = _f(c).copy()
    f = _f(f)[..., None] if np.ndim(f) else f
    c[..., :3] = c[..., :3] + f * (1.0 - 2.0 * c[..., :3])
    return c


def gamma(c, g):
    c = _f(c).copy()
    c[..., :3] = np.where(c[..., :3] > 0, compatible_pow(c[..., :3], g), c[..., :3])
    return c


def bright_contrast(c, bright, contrast):
    c = _f(c).copy()
    a = 1.0 + contrast
    b = bright - contrast * 0.5
    c[..., :3] = np.maximum(a * c[..., :3] + b, 0.0)
    return c


# --- converters -----------------------------------------------------------------------------


def _smootherstep(e0, e1, x):
    x = np.clip(safe_divide(x - e0, e1 - e0), 0.0, 1.0)
    return x * x * x * (x * (x * 6.0 - 15.0) + 10.0)


def _smoothstep(e0, e1, x):
    t = np.clip(safe_divide(x - e0, e1 - e0), 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


def map_range(kind, v, from_min, from_max, to_min, to_max, steps=4.0, clamp=True):
    v = _f(v)
    with np.errstate(all="ignore"):
        f = (v - from_min) / (from_max - from_min) if from_max != from_min else np.zeros_like(v)
        if kind == "STEPPED":
            f = np.floor(f * (steps + 1.0)) / steps if steps > 0 else np.zeros_like(v)
        elif kind == "SMOOTHSTEP":
            f = 1 - _smoothstep(from_max, from_min, v) if from_min > from_max else _smoothstep(from_min, from_max, v)
        elif kind == "SMOOTHERSTEP":
            f = (
                1 - _smootherstep(from_max, from_min, v)
                if from_min > from_max
                else _smootherstep(from_min, from_max, v)
            )
    r = to_min + f * (to_max - to_min)
    if clamp and kind in {"LINEAR", "STEPPED"}:
        r = np.clip(r, min(to_min, to_max), max(to_min, to_max))
    return np.where(from_max != from_min, r, 0.0)


def clamp(kind, v, lo, hi):
    if kind == "RANGE" and lo > hi:
        return np.clip(v, hi, lo)
    return np.minimum(np.maximum(v, lo), hi)


def _hue_interp(mode, fm, f, h1, h2):
    h1 = np.where(h1 < 1, h1, h1 - 1)
    h2 = np.where(h2 < 1, h2, h2 - 1)
    if mode == "NEAR":
        m = np.where((h1 < h2) & (h2 - h1 > 0.5), 1, np.where((h1 > h2) & (h2 - h1 < -0.5), 2, 0))
    elif mode == "FAR":
        m = np.where(
            h1 == h2, 1, np.where((h1 < h2) & (h2 - h1 < 0.5), 1, np.where((h1 > h2) & (h2 - h1 > -0.5), 2, 0))
        )
    elif mode == "CW":
        m = np.where(h1 < h2, 1, 0)
    else:
        m = np.where(h1 > h2, 2, 0)
    h = np.where(m == 1, fm * (h1 + 1) + f * h2, np.where(m == 2, fm * h1 + f * (h2 + 1), fm * h1 + f * h2))
    return np.where((m != 0) & (h >= 1), h - 1, h)


def color_ramp(x, positions, colors, interpolation="LINEAR", mode="RGB", hue="NEAR"):
    """Blender's colour band evaluated at each ``x`` (scalar loop: the tests' arrays are small)."""
    positions = [float(p) for p in positions]
    colors = [np.asarray(c, np.float64) for c in colors]
    n = len(positions)
    ip = interpolation if mode == "RGB" else "LINEAR"
    order = ("CONSTANT", "LINEAR", "EASE", "CARDINAL", "B_SPLINE")
    ipn = order.index(ip)
    out = np.zeros(np.shape(x) + (4,))
    flat = np.ravel(_f(x))
    res = out.reshape(-1, 4)
    for k, xv in enumerate(flat):
        if n == 1 or (xv <= positions[0] and ipn <= 2):
            res[k] = colors[0]
            continue
        a = next((i for i in range(n) if positions[i] > xv), n)
        i1 = min(a, n - 1)
        i2 = n - 1 if a == n else max(a - 1, 0)
        p1, p2 = positions[i1], (0.0 if a == 0 else positions[i2])
        if (a == n and ipn <= 2) or ipn == 0:
            res[k] = colors[i2]
            continue
        f = (xv - p1) / (p2 - p1) if p2 != p1 else (0.0 if a != n else 1.0)
        c1, c2 = colors[i1], colors[i2]
        if ipn >= 3:
            c0 = colors[i1 if a >= n - 1 else i1 + 1]
            c3 = colors[i2 if a < 2 else i2 - 1]
            f = min(max(f, 0.0), 1.0)
            t2, t3 = f * f, f * f * f
            if ipn == 3:
                fc = 0.71
                w = (
                    -fc * t3 + 2 * fc * t2 - fc * f,
                    (2 - fc) * t3 + (fc - 3) * t2 + 1,
                    (fc - 2) * t3 + (3 - 2 * fc) * t2 + fc * f,
                    fc * t3 - fc * t2,
                )
            else:
                w = (
                    -t3 / 6 + 0.5 * t2 - 0.5 * f + 1 / 6,
                    0.5 * t3 - t2 + 2 / 3,
                    -0.5 * t3 + 0.5 * t2 + 0.5 * f + 1 / 6,
                    t3 / 6,
                )
            res[k] = np.clip(w[3] * c3 + w[2] * c2 + w[1] * c1 + w[0] * c0, 0, 1)
            continue
        if ipn == 2:
            f = f * f * (3 - 2 * f)
        fm = 1 - f
        if mode == "RGB":
            res[k] = fm * c1 + f * c2
            continue
        to, back = (rgb_to_hsv, hsv_to_rgb) if mode == "HSV" else (rgb_to_hsl, hsl_to_rgb)
        h1, h2 = to(c1), to(c2)
        h = np.concatenate([[float(_hue_interp(hue, fm, f, h1[0], h2[0]))], fm * h1[1:] + f * h2[1:]])
        res[k] = back(h)
    return out


# --- input and textures ---------------------------------------------------------------------


def fresnel_dielectric(cosi, eta):
    c = np.abs(_f(cosi))
    g = eta * eta - 1.0 + c * c
    gs = np.sqrt(np.maximum(g, 0.0))
    with np.errstate(all="ignore"):
        a = (gs - c) / (gs + c)
        b = (c * (gs + c) - 1.0) / (c * (gs - c) + 1.0)
        r = 0.5 * a * a * (1.0 + b * b)
    return np.where(g > 0, r, 1.0)


def layer_weight(blend, cos_nv, front=True):
    eta = max(1.0 - blend, 1e-5)
    fresnel = fresnel_dielectric(cos_nv, 1.0 / eta if front else eta)
    facing = np.abs(_f(cos_nv))
    if blend != 0.5:
        b = min(max(blend, 0.0), 0.99999)
        b = 2.0 * b if b < 0.5 else 0.5 / (1.0 - b)
        facing = facing**b
    return fresnel, 1.0 - facing


def euler_to_matrix(e):
    cx, cy, cz = np.cos(e)
    sx, sy, sz = np.sin(e)
    # rows of the matrix (GLSL's columns transposed)
    return np.array(
        [
            [cy * cz, sy * sx * cz - cx * sz, sy * cx * cz + sx * sz],
            [cy * sz, sy * sx * sz + cx * cz, sy * cx * sz - sx * cz],
            [-sy, cy * sx, cy * cx],
        ]
    )


def mapping(kind, v, location, rotation, scale):
    v = _f(v)
    r = euler_to_matrix(_f(rotation))
    loc, scale = _f(location), _f(scale)
    if kind == "POINT":
        return (v * scale) @ r.T + loc
    if kind == "TEXTURE":
        return safe_divide((v - loc) @ r, scale)
    if kind == "VECTOR":
        return (v * scale) @ r.T
    return safe_normalize(safe_divide(v, scale) @ r.T)


def curve(mapping, curve_, x):
    """A CurveMapping curve evaluated by Blender itself at every ``x`` (the reference the
    tabulated node_curve is held to)."""
    mapping.initialize()
    flat = np.ravel(_f(x))
    return np.array([mapping.evaluate(curve_, float(v)) for v in flat]).reshape(np.shape(x))
