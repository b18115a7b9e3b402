"""numpy twins of the procedural textures in ``shaders/nodes/texture_*.glsl``, vectorised over
points: the same hashes on ``np.uint32`` / ``np.int32`` (wrapping), the same float32 arithmetic in
the same order, so GPU and numpy agree to float32 rounding and hashes agree bit for bit.

Points are arrays of shape (n, d) (d = 1..4, float32); results are float32 arrays. Parameters are
plain Python numbers. Enum values are the GLSL files' (``NOISE_*``, ``VORONOI_*``, ``WAVE_*``,
``MAGIC_*``, ``GRADIENT_*``)."""

import numpy as np

F = np.float32

NOISE_FBM, NOISE_MULTIFRACTAL, NOISE_HYBRID_MULTIFRACTAL, NOISE_RIDGED_MULTIFRACTAL, NOISE_HETERO_TERRAIN = range(5)
VORONOI_F1, VORONOI_F2, VORONOI_SMOOTH_F1, VORONOI_DISTANCE_TO_EDGE, VORONOI_N_SPHERE_RADIUS = range(5)
VORONOI_EUCLIDEAN, VORONOI_MANHATTAN, VORONOI_CHEBYCHEV, VORONOI_MINKOWSKI = range(4)
VORONOI_HASH_FLOAT, VORONOI_HASH_INT = range(2)
WAVE_BANDS, WAVE_RINGS = range(2)
WAVE_X, WAVE_Y, WAVE_Z, WAVE_DIAGONAL = range(4)
WAVE_SPHERICAL = WAVE_DIAGONAL
WAVE_SINE, WAVE_SAW, WAVE_TRIANGLE = range(3)
MAGIC_WRAP_UNSCALED, MAGIC_WRAP_SCALED = range(2)
(
    GRADIENT_LINEAR,
    GRADIENT_QUADRATIC,
    GRADIENT_EASING,
    GRADIENT_DIAGONAL,
    GRADIENT_SPHERICAL,
    GRADIENT_QUADRATIC_SPHERE,
    GRADIENT_RADIAL,
) = range(7)


def _f(x):
    return np.asarray(x, dtype=np.float32)


# --- hashes ---------------------------------------------------------------------------------


def _rotl(x, k):
    return (x << np.uint32(k)) | (x >> np.uint32(32 - k))


def _final(a, b, c):
    c = c ^ b
    c = c - _rotl(b, 14)
    a = a ^ c
    a = a - _rotl(c, 11)
    b = b ^ a
    b = b - _rotl(a, 25)
    c = c ^ b
    c = c - _rotl(b, 16)
    a = a ^ c
    a = a - _rotl(c, 4)
    b = b ^ a
    b = b - _rotl(a, 14)
    c = c ^ b
    c = c - _rotl(b, 24)
    return c


def hash_uint(*keys):
    """lookup3 of 1 to 4 uint32 words (arrays broadcast): Blender's hash_uint .. hash_uint4."""
    keys = [np.asarray(k).astype(np.uint32) for k in keys]
    n = len(keys)
    with np.errstate(over="ignore"):
        s = np.uint32((0xDEADBEEF + (n << 2) + 13) & 0xFFFFFFFF)
        shape = np.broadcast_shapes(*(k.shape for k in keys))
        a = np.full(shape, s, np.uint32) + keys[0]
        b = np.full(shape, s, np.uint32) + (keys[1] if n > 1 else np.uint32(0))
        c = np.full(shape, s, np.uint32) + (keys[2] if n > 2 else np.uint32(0))
        if n < 4:
            return _final(a, b, c)
        a = a - c
        a = a ^ _rotl(c, 4)
        c = c + b
        b = b - a
        b = b ^ _rotl(a, 6)
        a = a + c
        c = c - b
        c = c ^ _rotl(b, 8)
        b = b + a
        a = a - c
        a = a ^ _rotl(c, 16)
        c = c + b
        b = b - a
        b = b ^ _rotl(a, 19)
        a = a + c
        c = c - b
        c = c ^ _rotl(b, 4)
        b = b + a
        return _final(a + keys[3], b, c)


def _unit(h):
    return h.astype(np.float32) * F(2.0**-32)


def float_bits(x):
    return np.ascontiguousarray(_f(x)).view(np.uint32)


def hash_float(*values):
    """Blender's hash_float_to_float / hash_vec{2,3,4}_to_float: lookup3 of the float bits."""
    return _unit(hash_uint(*(float_bits(v) for v in values)))


def hash_float_vec3(p):
    """Blender's hash_{float,vec2,vec3,vec4}_to_vec3 of points (n, d)."""
    p = _f(p)
    d = p.shape[1]
    c = [p[:, i] for i in range(d)]
    one, two = np.ones_like(c[0]), np.full_like(c[0], 2.0)
    if d == 4:
        x, y, z, w = c
        return np.stack([hash_float(x, y, z, w), hash_float(z, x, w, y), hash_float(w, z, y, x)], -1)
    return np.stack([hash_float(*c), hash_float(*c, one), hash_float(*c, two)], -1)


def hash_float_vec(p):
    """Blender's hash_vec{2,3,4}_to_vec{2,3,4} (same dimension out as in)."""
    p = _f(p)
    d = p.shape[1]
    c = [p[:, i] for i in range(d)]
    if d == 2:
        return np.stack([hash_float(*c), hash_float(*c, np.ones_like(c[0]))], -1)
    if d == 3:
        return np.stack(
            [hash_float(*c), hash_float(*c, np.ones_like(c[0])), hash_float(*c, np.full_like(c[0], 2.0))], -1
        )
    x, y, z, w = c
    return np.stack(
        [hash_float(x, y, z, w), hash_float(w, x, y, z), hash_float(z, w, x, y), hash_float(y, z, w, x)], -1
    )


def hash_pcg(v):
    """Blender's signed PCG hash of int32 vectors (n, d), d = 2..4, masked to 31 bits."""
    v = np.asarray(v).astype(np.int32).copy()
    d = v.shape[1]
    m = np.int32(1664525)
    with np.errstate(over="ignore"):
        v = v * m + np.int32(1013904223)
        x = [v[:, i].copy() for i in range(d)]

        def rounds(x):
            if d == 2:
                x[0] += x[1] * m
                x[1] += x[0] * m
            elif d == 3:
                x[0] += x[1] * x[2]
                x[1] += x[2] * x[0]
                x[2] += x[0] * x[1]
            else:
                x[0] += x[1] * x[3]
                x[1] += x[2] * x[0]
                x[2] += x[0] * x[1]
                x[3] += x[1] * x[2]

        rounds(x)
        x = [xi ^ (xi >> np.int32(16)) for xi in x]
        rounds(x)
    return np.stack([xi & np.int32(0x7FFFFFFF) for xi in x], -1)


def hash_int_vec(v):
    """Blender's hash_int{2,3,4}_to_vec{2,3,4}."""
    return hash_pcg(v).astype(np.float32) * F(2.0**-31)


def hash_int_vec3(v):
    """Blender's hash_int{2,4}_to_vec3 (and hash_int3_to_vec3)."""
    v = np.asarray(v).astype(np.int32)
    if v.shape[1] == 2:
        v = np.concatenate([v, np.zeros_like(v[:, :1])], 1)
    return hash_int_vec(v)[:, :3]


def finite(x):
    """Non-finite values read as 0 (the GLSL side's texture_finite)."""
    x = _f(x)
    return np.where(np.isfinite(x), x, F(0.0)).astype(np.float32)


def _scaled(x, scale):
    """finite(x) * scale in float32; an overflow gives inf, as on the GPU."""
    with np.errstate(over="ignore"):
        return finite(x) * F(scale)


# --- gradient noise -------------------------------------------------------------------------


def _fade(t):
    return t * t * t * (t * (t * F(6.0) - F(15.0)) + F(10.0))


def _grad(h, f):
    """Blender's gradient of each dimension: h uint32 hashes, f list of per-axis offsets."""
    d = len(f)
    if d == 1:
        h = h & np.uint32(15)
        g = (np.uint32(1) + (h & np.uint32(7))).astype(np.float32)
        return np.where(h & np.uint32(8), -g, g) * f[0]
    if d == 2:
        h = h & np.uint32(7)
        u = np.where(h < 4, f[0], f[1])
        v = F(2.0) * np.where(h < 4, f[1], f[0])
        return np.where(h & np.uint32(1), -u, u) + np.where(h & np.uint32(2), -v, v)
    if d == 3:
        h = h & np.uint32(15)
        u = np.where(h < 8, f[0], f[1])
        vt = np.where((h == 12) | (h == 14), f[0], f[2])
        v = np.where(h < 4, f[1], vt)
        return np.where(h & np.uint32(1), -u, u) + np.where(h & np.uint32(2), -v, v)
    h = h & np.uint32(31)
    u = np.where(h < 24, f[0], f[1])
    v = np.where(h < 16, f[1], f[2])
    s = np.where(h < 8, f[2], f[3])
    return np.where(h & np.uint32(1), -u, u) + np.where(h & np.uint32(2), -v, v) + np.where(h & np.uint32(4), -s, s)


def _mix(a, b, t):
    return a * (F(1.0) - t) + b * t


def perlin(p):
    """Unscaled gradient noise of wrapped points (n, d)."""
    p = _f(p)
    d = p.shape[1]
    pf = np.floor(p)
    cell = pf.astype(np.int32)
    fr = (p - pf).astype(np.float32)
    fx = [fr[:, i] for i in range(d)]
    u = [_fade(x) for x in fx]

    def corner(bits):
        keys = [(cell[:, i] + np.int32((bits >> i) & 1)).view(np.uint32) for i in range(d)]
        offs = [fx[i] - F((bits >> i) & 1) for i in range(d)]
        return _grad(hash_uint(*keys), offs)

    v = [corner(b) for b in range(1 << d)]
    if d == 1:
        return _mix(v[0], v[1], u[0])

    def lerp3(v, base):
        x1, y1, z1 = F(1.0) - u[0], F(1.0) - u[1], F(1.0) - u[2]
        x, y, z = u[0], u[1], u[2]
        w = v[base : base + 8]
        return z1 * (y1 * (w[0] * x1 + w[1] * x) + y * (w[2] * x1 + w[3] * x)) + z * (
            y1 * (w[4] * x1 + w[5] * x) + y * (w[6] * x1 + w[7] * x)
        )

    if d == 2:
        x1 = F(1.0) - u[0]
        return (F(1.0) - u[1]) * (v[0] * x1 + v[1] * u[0]) + u[1] * (v[2] * x1 + v[3] * u[0])
    if d == 3:
        return lerp3(v, 0)
    return _mix(lerp3(v, 0), lerp3(v, 8), u[3])


_NOISE_SCALE = {1: F(0.25), 2: F(0.6616), 3: F(0.9820), 4: F(0.8344)}


def snoise(p):
    """Blender's signed noise snoise_1d .. _4d of points (n, d); non-finite points give 0."""
    p = _f(p)
    ok = np.all(np.isfinite(p), axis=1)
    q = np.where(np.isfinite(p), p, F(0.0))
    wrapped = (np.fmod(q, F(100000.0)) + np.where(np.abs(q) >= F(1000000.0), F(0.5), F(0.0))).astype(np.float32)
    return np.where(ok, _NOISE_SCALE[p.shape[1]] * perlin(wrapped), F(0.0)).astype(np.float32)


def noise_fbm(p, detail, roughness, lacunarity, normalize):
    p = _f(p)
    fscale, amp, maxamp = F(1.0), F(1.0), F(0.0)
    roughness, lacunarity, detail = F(roughness), F(lacunarity), F(detail)
    total = np.zeros(len(p), np.float32)
    for _ in range(int(detail) + 1):
        total = total + snoise(fscale * p) * amp
        maxamp = F(maxamp + amp)
        amp = F(amp * roughness)
        fscale = F(fscale * lacunarity)
    rmd = F(detail - np.floor(detail))
    if rmd != 0:
        sum2 = total + snoise(fscale * p) * amp
        if normalize:
            return _mix(F(0.5) * total / maxamp + F(0.5), F(0.5) * sum2 / F(maxamp + amp) + F(0.5), rmd)
        return _mix(total, sum2, rmd)
    return F(0.5) * total / maxamp + F(0.5) if normalize else total


def noise_multi_fractal(p, detail, roughness, lacunarity):
    p = _f(p)
    value = np.ones(len(p), np.float32)
    pwr = F(1.0)
    for _ in range(int(detail) + 1):
        value = value * (pwr * snoise(p) + F(1.0))
        pwr = F(pwr * F(roughness))
        p = p * F(lacunarity)
    rmd = F(F(detail) - np.floor(F(detail)))
    if rmd != 0:
        value = value * (rmd * pwr * snoise(p) + F(1.0))
    return value


def noise_hetero_terrain(p, detail, roughness, lacunarity, offset):
    p = _f(p)
    offset = F(offset)
    pwr = F(roughness)
    value = offset + snoise(p)
    p = p * F(lacunarity)
    for _ in range(1, int(detail) + 1):
        value = value + (snoise(p) + offset) * pwr * value
        pwr = F(pwr * F(roughness))
        p = p * F(lacunarity)
    rmd = F(F(detail) - np.floor(F(detail)))
    if rmd != 0:
        value = value + rmd * ((snoise(p) + offset) * pwr * value)
    return value


def noise_hybrid_multi_fractal(p, detail, roughness, lacunarity, offset, gain):
    p = _f(p)
    offset, gain = F(offset), F(gain)
    pwr = F(1.0)
    value = np.zeros(len(p), np.float32)
    weight = np.ones(len(p), np.float32)
    for _ in range(int(detail) + 1):
        live = weight > F(0.001)  # the loop stops per point once its weight is spent
        weight = np.where(live, np.minimum(weight, F(1.0)), weight)
        signal = (snoise(p) + offset) * pwr
        value = np.where(live, value + weight * signal, value)
        weight = np.where(live, weight * (gain * signal), weight)
        pwr = F(pwr * F(roughness))
        p = np.where(live[:, None], p * F(lacunarity), p)
    rmd = F(F(detail) - np.floor(F(detail)))
    if rmd != 0:
        live = weight > F(0.001)
        weight = np.minimum(weight, F(1.0))
        # pwr of a point that stopped early is smaller; it is only used where live
        value = np.where(live, value + rmd * weight * ((snoise(p) + offset) * pwr), value)
    return value


def noise_ridged_multi_fractal(p, detail, roughness, lacunarity, offset, gain):
    p = _f(p)
    offset, gain = F(offset), F(gain)
    pwr = F(roughness)
    signal = offset - np.abs(snoise(p))
    signal = signal * signal
    value = signal
    for _ in range(1, int(detail) + 1):
        p = p * F(lacunarity)
        weight = np.clip(signal * gain, F(0.0), F(1.0))
        signal = offset - np.abs(snoise(p))
        signal = signal * signal
        signal = signal * weight
        value = value + signal * pwr
        pwr = F(pwr * F(roughness))
    return value


def noise_select(p, detail, roughness, lacunarity, offset, gain, kind, normalize):
    if kind == NOISE_MULTIFRACTAL:
        return noise_multi_fractal(p, detail, roughness, lacunarity)
    if kind == NOISE_HYBRID_MULTIFRACTAL:
        return noise_hybrid_multi_fractal(p, detail, roughness, lacunarity, offset, gain)
    if kind == NOISE_RIDGED_MULTIFRACTAL:
        return noise_ridged_multi_fractal(p, detail, roughness, lacunarity, offset, gain)
    if kind == NOISE_HETERO_TERRAIN:
        return noise_hetero_terrain(p, detail, roughness, lacunarity, offset)
    return noise_fbm(p, detail, roughness, lacunarity, normalize)


def _seed_offset(seed, d):
    if d == 1:
        return _f([F(100.0) + F(100.0) * hash_float(_f([seed]))[0]])
    return _f([F(100.0) + F(100.0) * hash_float(_f([seed]), _f([axis]))[0] for axis in range(d)])


def _node_point(dimensions, vector, w):
    vector, w = _f(vector).reshape(-1, 3), _f(w).reshape(-1)
    if dimensions == 1:
        return w[:, None]
    if dimensions == 2:
        return vector[:, :2]
    if dimensions == 3:
        return vector
    return np.concatenate([vector, w[:, None]], 1)


def node_tex_noise(
    dimensions,
    vector,
    w,
    scale=5.0,
    detail=2.0,
    roughness=0.5,
    lacunarity=2.0,
    offset=0.0,
    gain=1.0,
    distortion=0.0,
    kind=NOISE_FBM,
    normalize=True,
):
    """The Noise Texture node: (n, 4) with Color in [:, :3] and Fac in [:, 3]."""
    detail = float(np.clip(F(detail), 0.0, 15.0))
    roughness = max(F(roughness), F(0.0))
    p = _node_point(dimensions, _scaled(vector, scale), _scaled(w, scale))
    d = p.shape[1]
    if distortion != 0.0:
        first = 0
        p = p + np.stack([snoise(p + _seed_offset(first + i, d)) * F(distortion) for i in range(d)], -1)
    seeds = (1, 2) if d == 1 else (d, d + 1)
    args = (detail, roughness, lacunarity, offset, gain, kind, normalize)
    value = noise_select(p, *args)
    g = noise_select(p + _seed_offset(seeds[0], d), *args)
    b = noise_select(p + _seed_offset(seeds[1], d), *args)
    return np.stack([value, g, b, value], -1).astype(np.float32)


# --- white noise ----------------------------------------------------------------------------


def node_tex_white_noise(dimensions, vector, w):
    """The White Noise Texture node: (n, 4), Color in [:, :3], Value in [:, 3]."""
    p = _node_point(dimensions, vector, w)
    value = hash_float(*(p[:, i] for i in range(p.shape[1])))
    return np.concatenate([hash_float_vec3(p), value[:, None]], 1).astype(np.float32)


# --- Voronoi --------------------------------------------------------------------------------

_FLT_MAX = F(3.402823466e38)


def _cell_int(cf):
    """float cell -> int32 as x86 converts (out of range: INT_MIN)."""
    ok = np.abs(cf) < F(2147483648.0)
    return np.where(ok, np.where(ok, cf, F(0.0)).astype(np.int32), np.int32(-(2**31))).astype(np.int32)


def _offsets(d, r):
    """Neighbour offsets of a (2r+1)^d window, x fastest (Blender's loop order)."""
    s = 2 * r + 1
    return [np.array([(n // s**i) % s - r for i in range(d)], np.int32) for n in range(s**d)]


def voronoi_distance(a, b, metric, exponent):
    """Blender's metrics between points (n, d); 1D is |a - b| whatever the metric."""
    diff = np.abs(a - b).astype(np.float32)
    if a.shape[1] == 1:
        return diff[:, 0]
    if metric == VORONOI_MANHATTAN:
        return _sum(diff)
    if metric == VORONOI_CHEBYCHEV:
        return diff.max(axis=1)
    if metric == VORONOI_MINKOWSKI:
        e = F(exponent)
        return np.power(_sum(np.power(diff, e)), F(1.0) / e).astype(np.float32)
    return np.sqrt(_sum(diff * diff)).astype(np.float32)


def _sum(v):
    out = v[:, 0]
    for i in range(1, v.shape[1]):
        out = out + v[:, i]
    return out


class _Cells:
    """The cell of each point and its feature points' jitter and colour, as Blender's version
    hashes them (1D: always lookup3 of the float cell)."""

    def __init__(self, coord, hash_mode):
        self.cell_f = np.floor(coord).astype(np.float32)
        self.local = (coord - self.cell_f).astype(np.float32)
        self.cell_i = _cell_int(self.cell_f)
        self.d = coord.shape[1]
        self.mode = hash_mode

    def jitter(self, o):
        if self.d == 1:
            return hash_float(self.cell_f[:, 0] + F(o[0]))[:, None]
        if self.mode == VORONOI_HASH_INT:
            with np.errstate(over="ignore"):
                return hash_int_vec(self.cell_i + o)
        return hash_float_vec(self.cell_f + o.astype(np.float32))

    def color(self, o):
        """o: one offset (d,) or per-point offsets (n, d)."""
        if self.d == 1:
            return hash_float_vec3(self.cell_f + np.asarray(o, np.float32).reshape(-1, 1))
        if self.mode == VORONOI_HASH_INT:
            with np.errstate(over="ignore"):
                return hash_int_vec3(self.cell_i + o)
        return hash_float_vec3(self.cell_f + np.asarray(o).astype(np.float32))

    def point(self, o, randomness):
        return (o.astype(np.float32) + self.jitter(o) * F(randomness)).astype(np.float32)


def _position(p):
    n, d = p.shape
    out = np.zeros((n, 4), np.float32)
    if d == 1:
        out[:, 3] = p[:, 0]
    else:
        out[:, :d] = p
    return out


def voronoi_f1(coord, metric, exponent, randomness, hash_mode):
    c = _Cells(coord, hash_mode)
    n = len(coord)
    best = np.full(n, _FLT_MAX, np.float32)
    target_o = np.zeros((n, c.d), np.int32)
    target_p = np.zeros((n, c.d), np.float32)
    for o in _offsets(c.d, 1):
        p = c.point(o, randomness)
        dist = voronoi_distance(p, c.local, metric, exponent)
        closer = dist < best
        best = np.where(closer, dist, best)
        target_o = np.where(closer[:, None], o, target_o)
        target_p = np.where(closer[:, None], p, target_p)
    return best, c.color(target_o), _position(target_p + c.cell_f)


def voronoi_f2(coord, metric, exponent, randomness, hash_mode):
    c = _Cells(coord, hash_mode)
    n = len(coord)
    d1 = np.full(n, _FLT_MAX, np.float32)
    d2 = d1.copy()
    o1 = np.zeros((n, c.d), np.int32)
    o2, p1, p2 = o1.copy(), np.zeros((n, c.d), np.float32), np.zeros((n, c.d), np.float32)
    for o in _offsets(c.d, 1):
        p = c.point(o, randomness)
        dist = voronoi_distance(p, c.local, metric, exponent)
        first = dist < d1
        second = ~first & (dist < d2)
        f, s = first[:, None], second[:, None]
        d2 = np.where(first, d1, np.where(second, dist, d2))
        o2 = np.where(f, o1, np.where(s, o, o2))
        p2 = np.where(f, p1, np.where(s, p, p2))
        d1 = np.where(first, dist, d1)
        o1 = np.where(f, o, o1)
        p1 = np.where(f, p, p1)
    return d2, c.color(o2), _position(p2 + c.cell_f)


def _smoothstep(e0, e1, x):
    t = np.clip((x - e0) / (e1 - e0), F(0.0), F(1.0))
    return t * t * (F(3.0) - F(2.0) * t)


def voronoi_smooth_f1(coord, metric, exponent, randomness, smoothness, hash_mode):
    c = _Cells(coord, hash_mode)
    n = len(coord)
    s = F(smoothness)
    sd = np.zeros(n, np.float32)
    sc = np.zeros((n, 3), np.float32)
    sp = np.zeros((n, c.d), np.float32)
    first = True
    for o in _offsets(c.d, 2):
        p = c.point(o, randomness)
        dist = voronoi_distance(p, c.local, metric, exponent)
        h = np.ones(n, np.float32) if first else _smoothstep(F(0.0), F(1.0), F(0.5) + F(0.5) * (sd - dist) / s)
        first = False
        corr = s * h * (F(1.0) - h)
        sd = _mix(sd, dist, h) - corr
        corr = corr / (F(1.0) + F(3.0) * s)
        sc = _mix(sc, c.color(o), h[:, None]) - corr[:, None]
        sp = _mix(sp, p, h[:, None]) - corr[:, None]
    return sd, sc, _position(c.cell_f + sp)


def voronoi_distance_to_edge(coord, randomness, hash_mode):
    c = _Cells(coord, hash_mode)
    n = len(coord)
    if c.d == 1:
        r = F(randomness)
        mid = c.jitter(np.array([0]))[:, 0] * r
        left = F(-1.0) + c.jitter(np.array([-1]))[:, 0] * r
        right = F(1.0) + c.jitter(np.array([1]))[:, 0] * r
        x = c.local[:, 0]
        return np.minimum(np.abs((mid + left) / F(2.0) - x), np.abs((mid + right) / F(2.0) - x))
    vectors = [c.point(o, randomness) - c.local for o in _offsets(c.d, 1)]
    best = np.full(n, _FLT_MAX, np.float32)
    closest = np.zeros((n, c.d), np.float32)
    for v in vectors:
        dist = _sum(v * v)
        closer = dist < best
        best = np.where(closer, dist, best)
        closest = np.where(closer[:, None], v, closest)
    best = np.full(n, _FLT_MAX, np.float32)
    for v in vectors:
        perp = v - closest
        length2 = _sum(perp * perp)
        use = length2 > F(0.0001)
        with np.errstate(invalid="ignore", divide="ignore"):
            unit = perp / np.sqrt(length2)[:, None]
            edge = _sum(((closest + v) / F(2.0)) * unit)
        best = np.where(use, np.minimum(best, edge), best)
    return best


def voronoi_n_sphere_radius(coord, randomness, hash_mode):
    c = _Cells(coord, hash_mode)
    n = len(coord)
    best = np.full(n, _FLT_MAX, np.float32)
    closest = np.zeros((n, c.d), np.float32)
    closest_o = np.zeros((n, c.d), np.int32)
    for o in _offsets(c.d, 1):
        p = c.point(o, randomness)
        dist = voronoi_distance(p, c.local, VORONOI_EUCLIDEAN, 1.0)
        closer = dist < best
        best = np.where(closer, dist, best)
        closest = np.where(closer[:, None], p, closest)
        closest_o = np.where(closer[:, None], o, closest_o)
    best = np.full(n, _FLT_MAX, np.float32)
    second = np.zeros((n, c.d), np.float32)
    for o in _offsets(c.d, 1):
        if not o.any():
            continue
        oo = o + closest_o
        with np.errstate(over="ignore"):
            if c.d == 1:
                jit = hash_float(c.cell_f[:, 0] + oo[:, 0].astype(np.float32))[:, None]
            elif c.mode == VORONOI_HASH_INT:
                jit = hash_int_vec(c.cell_i + oo)
            else:
                jit = hash_float_vec(c.cell_f + oo.astype(np.float32))
        p = (oo.astype(np.float32) + jit * F(randomness)).astype(np.float32)
        dist = voronoi_distance(closest, p, VORONOI_EUCLIDEAN, 1.0)
        closer = dist < best
        best = np.where(closer, dist, best)
        second = np.where(closer[:, None], p, second)
    return voronoi_distance(second, closest, VORONOI_EUCLIDEAN, 1.0) / F(2.0)


def voronoi_fractal(coord, feature, metric, exponent, randomness, smoothness, detail, roughness, lacunarity,
                    normalize, max_distance, scale, hash_mode):  # fmt: skip
    """Blender's fractal_voronoi_x_fx: (distance, colour (n, 3), position (n, 4))."""
    n = len(coord)
    amplitude, max_amplitude, octave_scale = F(1.0), F(0.0), F(1.0)
    detail, roughness, lacunarity = F(detail), F(roughness), F(lacunarity)
    dist = np.zeros(n, np.float32)
    color = np.zeros((n, 3), np.float32)
    position = np.zeros((n, 4), np.float32)
    zero_input = detail == 0 or roughness == 0
    for i in range(int(np.ceil(detail)) + 1):
        with np.errstate(over="ignore"):
            c = finite(coord * octave_scale)
        if feature == VORONOI_F2:
            od, oc, op = voronoi_f2(c, metric, exponent, randomness, hash_mode)
        elif feature == VORONOI_SMOOTH_F1 and smoothness != 0:
            od, oc, op = voronoi_smooth_f1(c, metric, exponent, randomness, smoothness, hash_mode)
        else:
            od, oc, op = voronoi_f1(c, metric, exponent, randomness, hash_mode)
        if zero_input:
            max_amplitude, dist, color, position = F(1.0), od, oc, op
            break
        if i <= detail:
            max_amplitude = F(max_amplitude + amplitude)
            dist = dist + od * amplitude
            color = color + oc * amplitude
            position = _mix(position, op / octave_scale, amplitude)
            octave_scale = F(octave_scale * lacunarity)
            amplitude = F(amplitude * roughness)
        else:
            rem = F(detail - np.floor(detail))
            if rem != 0:
                max_amplitude = _mix(max_amplitude, F(max_amplitude + amplitude), rem)
                dist = _mix(dist, dist + od * amplitude, rem)
                color = _mix(color, color + oc * amplitude, rem)
                position = _mix(position, _mix(position, op / octave_scale, amplitude), rem)
    if normalize:
        dist = dist / (max_amplitude * F(max_distance))
        color = color / max_amplitude
    position = position / F(scale) if scale != 0 else np.zeros_like(position)
    return dist.astype(np.float32), color.astype(np.float32), position.astype(np.float32)


def voronoi_fractal_edge(coord, randomness, detail, roughness, lacunarity, normalize, max_distance, hash_mode):
    amplitude, octave_scale = F(1.0), F(1.0)
    detail, roughness, lacunarity, max_distance = F(detail), F(roughness), F(lacunarity), F(max_distance)
    max_amplitude = max_distance
    dist = np.full(len(coord), 8.0, np.float32)
    zero_input = detail == 0 or roughness == 0
    for i in range(int(np.ceil(detail)) + 1):
        with np.errstate(over="ignore"):
            c = finite(coord * octave_scale)
        od = voronoi_distance_to_edge(c, randomness, hash_mode)
        if zero_input:
            dist = od
            break
        if i <= detail:
            max_amplitude = _mix(max_amplitude, max_distance / octave_scale, amplitude)
            dist = _mix(dist, np.minimum(dist, od / octave_scale), amplitude)
            octave_scale = F(octave_scale * lacunarity)
            amplitude = F(amplitude * roughness)
        else:
            rem = F(detail - np.floor(detail))
            if rem != 0:
                lerp_amplitude = _mix(max_amplitude, max_distance / octave_scale, amplitude)
                max_amplitude = _mix(max_amplitude, lerp_amplitude, rem)
                lerp_d = _mix(dist, np.minimum(dist, od / octave_scale), amplitude)
                dist = _mix(dist, np.minimum(dist, lerp_d), rem)
    return dist / max_amplitude if normalize else dist


def node_tex_voronoi(
    dimensions,
    vector,
    w,
    feature=VORONOI_F1,
    metric=VORONOI_EUCLIDEAN,
    scale=5.0,
    detail=0.0,
    roughness=0.5,
    lacunarity=2.0,
    smoothness=1.0,
    exponent=0.5,
    randomness=1.0,
    normalize=False,
    hash_mode=VORONOI_HASH_INT,
):
    """The Voronoi Texture node: (n, 8) = Distance, Color (3), Position (3), W; or, for N-Sphere
    Radius, Radius in column 0."""
    detail = float(np.clip(F(detail), 0.0, 15.0))
    roughness = float(np.clip(F(roughness), 0.0, 1.0))
    randomness = float(np.clip(F(randomness), 0.0, 1.0))
    smoothness = float(np.clip(F(smoothness) / F(2.0), 0.0, 0.5))
    p = _node_point(dimensions, finite(_scaled(vector, scale)), finite(_scaled(w, scale)))
    out = np.zeros((len(p), 8), np.float32)
    half = F(F(0.5) + F(0.5) * F(randomness))
    if feature == VORONOI_DISTANCE_TO_EDGE:
        out[:, 0] = voronoi_fractal_edge(p, randomness, detail, roughness, lacunarity, normalize, half, hash_mode)
        return out
    if feature == VORONOI_N_SPHERE_RADIUS:
        out[:, 0] = voronoi_n_sphere_radius(p, randomness, hash_mode)
        return out
    f2 = F(2.0) if feature == VORONOI_F2 else F(1.0)
    if dimensions == 1:
        max_distance = half * f2
    else:
        max_distance = (
            voronoi_distance(np.zeros((1, dimensions), np.float32), np.full((1, dimensions), half), metric, exponent)[0]
            * f2
        )
    dist, color, pos = voronoi_fractal(p, feature, metric, exponent, randomness, smoothness, detail, roughness,
                                       lacunarity, normalize, max_distance, scale, hash_mode)  # fmt: skip
    out[:, 0] = dist
    out[:, 1:4] = color
    out[:, 4:7] = pos[:, :3]
    out[:, 7] = pos[:, 3]
    return out


# --- Wave, Magic, Brick, Checker, Gradient ---------------------------------------------------

_TWO_PI = F(6.2831853071795864)
_HALF_PI = F(1.5707963267948966)


def float_to_int(f):
    """C's (int)f as x86 converts it (INT_MIN out of range): the GLSL texture_float_to_int."""
    return _cell_int(_f(f))


def _nudge(p):
    return ((p + F(0.000001)) * F(0.999999)).astype(np.float32)


def texture_wave(p, distortion, detail, detail_scale, detail_roughness, phase, kind, direction, profile):
    """The wave of already scaled points (n, 3)."""
    p = _nudge(_f(p))
    x, y, z = p[:, 0], p[:, 1], p[:, 2]
    with np.errstate(over="ignore", invalid="ignore"):
        if kind == WAVE_BANDS:
            n = [x * F(20.0), y * F(20.0), z * F(20.0), (x + y + z) * F(10.0)][direction]
        else:
            r = [np.zeros_like(c) if direction == i else c for i, c in enumerate((x, y, z))]
            n = np.sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]) * F(20.0)
        n = n + F(phase)
        if distortion != 0.0:
            f = noise_fbm(finite(p * F(detail_scale)), float(np.clip(F(detail), 0.0, 15.0)),
                          max(F(detail_roughness), F(0.0)), 2.0, True)  # fmt: skip
            n = n + F(distortion) * (f * F(2.0) - F(1.0))
        n = finite(n)
        # Clamped to [0, 1] as the shader does (sin's rounding, n + 0.5 rounding up from 2^23).
        if profile == WAVE_SINE:
            return np.clip(F(0.5) + F(0.5) * np.sin(n - _HALF_PI), F(0.0), F(1.0)).astype(np.float32)
        n = n / _TWO_PI
        if profile == WAVE_SAW:
            return np.clip(n - np.floor(n), F(0.0), F(1.0)).astype(np.float32)
        return np.clip(np.abs(n - np.floor(n + F(0.5))) * F(2.0), F(0.0), F(1.0)).astype(np.float32)


def node_tex_wave(
    vector,
    scale=5.0,
    distortion=0.0,
    detail=2.0,
    detail_scale=1.0,
    detail_roughness=0.5,
    phase=0.0,
    kind=WAVE_BANDS,
    direction=WAVE_X,
    profile=WAVE_SINE,
):
    """The Wave Texture node: (n, 4), Color in [:, :3], Fac in [:, 3]; ``direction`` is the
    bands' or the rings' direction, whichever ``kind`` uses."""
    p = finite(_scaled(vector, scale))
    f = texture_wave(p, distortion, detail, detail_scale, detail_roughness, phase, kind, direction, profile)
    return np.stack([f, f, f, f], -1)


def node_tex_magic(vector, scale=5.0, distortion=1.0, depth=2, wrap=MAGIC_WRAP_SCALED):
    """The Magic Texture node: (n, 4), Color in [:, :3], Fac in [:, 3]. ``wrap``: where the scale
    enters (MAGIC_WRAP_UNSCALED: Blender 4.5, MAGIC_WRAP_SCALED: Blender 5)."""
    p = finite(vector)
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        if wrap == MAGIC_WRAP_SCALED:
            p = finite(p * F(scale))
        p = np.fmod(p, _TWO_PI).astype(np.float32)
        px, py, pz = p[:, 0], p[:, 1], p[:, 2]
        a = [(px + py + pz) * F(5.0), (-px + py - pz) * F(5.0), (-px - py + pz) * F(5.0)]
        if wrap == MAGIC_WRAP_UNSCALED:
            a = [finite(v * F(scale)) for v in a]
        x, y, z = np.sin(a[0]), np.cos(a[1]), -np.cos(a[2])
        d = F(distortion)
        depth = int(np.clip(depth, 0, 10))
        if depth > 0:
            x, y, z = x * d, y * d, z * d
            y = -np.cos(x - y + z) * d
        if depth > 1:
            x = np.cos(x - y - z) * d
        if depth > 2:
            z = np.sin(-x - y - z) * d
        if depth > 3:
            x = -np.cos(-x + y - z) * d
        if depth > 4:
            y = -np.sin(-x + y + z) * d
        if depth > 5:
            y = -np.cos(-x + y + z) * d
        if depth > 6:
            x = np.cos(x + y + z) * d
        if depth > 7:
            z = np.sin(x + y - z) * d
        if depth > 8:
            x = -np.cos(-x - y + z) * d
        if depth > 9:
            y = -np.sin(x - y + z) * d
        if d != 0.0:
            x, y, z = x / (d * F(2.0)), y / (d * F(2.0)), z / (d * F(2.0))
        color = [F(0.5) - x, F(0.5) - y, F(0.5) - z]
        fac = (color[0] + color[1] + color[2]) * F(1.0 / 3.0)
    return np.stack(color + [fac], -1).astype(np.float32)


def brick_noise(n):
    """Blender's integer noise of the Brick texture, of uint32 n, in [0, 1)."""
    n = np.asarray(n).astype(np.uint32)
    with np.errstate(over="ignore"):
        n = (n + np.uint32(1013)) & np.uint32(0x7FFFFFFF)
        n = (n >> np.uint32(13)) ^ n
        m = (n * (n * n * np.uint32(60493) + np.uint32(19990303)) + np.uint32(1376312589)) & np.uint32(0x7FFFFFFF)
    return (F(0.5) * (m.astype(np.float32) / F(1073741824.0))).astype(np.float32)


def _row_is_multiple(row, frequency):
    magnitude = np.abs(row.astype(np.int64))
    return magnitude % frequency == 0


def _smoothstep01(t):
    return np.where(t <= 0, F(0.0), np.where(t >= 1, F(1.0), (F(3.0) - F(2.0) * t) * t * t)).astype(np.float32)


def texture_brick(p, mortar_size, mortar_smooth, bias, brick_width, row_height, offset_amount, offset_frequency,
                  squash_amount, squash_frequency):  # fmt: skip
    """(tint, mortar) of already scaled points (n, 3)."""
    p = _f(p)
    row_height = F(row_height)
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        row = float_to_int(np.floor(p[:, 1] / row_height))
        width = np.full(len(p), F(brick_width), np.float32)
        offset = np.zeros(len(p), np.float32)
        if offset_frequency != 0 and squash_frequency != 0:
            width = np.where(_row_is_multiple(row, squash_frequency), width * F(squash_amount), width)
            offset = np.where(_row_is_multiple(row, offset_frequency), width * F(offset_amount), offset)
        shifted = (p[:, 0] + offset).astype(np.float32)
        brick = float_to_int(np.floor(shifted / width))
        x = shifted - width * brick.astype(np.float32)
        y = p[:, 1] - row_height * row.astype(np.float32)
        key = (row.astype(np.int64) << 16) + (brick.astype(np.int64) & 0xFFFF)
        tint = np.clip(brick_noise((key & 0xFFFFFFFF).astype(np.uint32)) + F(bias), F(0.0), F(1.0))
        min_dist = np.minimum(np.minimum(x, y), np.minimum(width - x, row_height - y))
        if mortar_smooth == 0.0:
            inside = F(1.0)
        else:
            inside = _smoothstep01((F(1.0) - min_dist / F(mortar_size)) / F(mortar_smooth))
        mortar = np.where(min_dist >= F(mortar_size), F(0.0), inside)
    return tint.astype(np.float32), mortar.astype(np.float32)


def node_tex_brick(
    vector,
    color1=(0.8, 0.8, 0.8),
    color2=(0.2, 0.2, 0.2),
    mortar=(0.0, 0.0, 0.0),
    scale=5.0,
    mortar_size=0.02,
    mortar_smooth=0.1,
    bias=0.0,
    brick_width=0.5,
    row_height=0.25,
    offset_amount=0.5,
    offset_frequency=2,
    squash_amount=1.0,
    squash_frequency=2,
):
    """The Brick Texture node: (n, 4), Color in [:, :3], Fac in [:, 3]."""
    p = finite(_scaled(vector, scale))
    tint, f = texture_brick(p, mortar_size, mortar_smooth, bias, brick_width, row_height, offset_amount,
                            offset_frequency, squash_amount, squash_frequency)  # fmt: skip
    c1, c2, m = _f(color1), _f(color2), _f(mortar)
    t = tint[:, None]
    brick = np.where((f != F(1.0))[:, None], (F(1.0) - t) * c1 + t * c2, c1)
    color = brick * (F(1.0) - f[:, None]) + m * f[:, None]
    return np.concatenate([color, f[:, None]], 1).astype(np.float32)


def node_tex_checker(vector, color1=(0.8, 0.8, 0.8), color2=(0.2, 0.2, 0.2), scale=5.0):
    """The Checker Texture node: (n, 4), Color in [:, :3], Fac in [:, 3]."""
    p = _nudge(finite(_scaled(vector, scale)))
    with np.errstate(invalid="ignore"):
        parity = [float_to_int(np.floor(p[:, i])) & 1 for i in range(3)]
    f = np.where((parity[0] == parity[1]) == (parity[2] == 1), F(1.0), F(0.0)).astype(np.float32)
    color = np.where((f == F(1.0))[:, None], _f(color1), _f(color2))
    return np.concatenate([color, f[:, None]], 1).astype(np.float32)


def texture_gradient(p, kind):
    """The unclamped gradient of points (n, 3)."""
    p = _f(p)
    x, y, z = p[:, 0], p[:, 1], p[:, 2]
    with np.errstate(over="ignore", invalid="ignore"):
        if kind == GRADIENT_LINEAR:
            return x
        if kind == GRADIENT_QUADRATIC:
            r = np.maximum(x, F(0.0))
            return r * r
        if kind == GRADIENT_EASING:
            r = np.clip(x, F(0.0), F(1.0))
            t = r * r
            return F(3.0) * t - F(2.0) * t * r
        if kind == GRADIENT_DIAGONAL:
            return (x + y) * F(0.5)
        if kind == GRADIENT_RADIAL:
            return np.arctan2(y, x) / _TWO_PI + F(0.5)
        r = np.maximum(F(0.999999) - np.sqrt(x * x + y * y + z * z), F(0.0))
        if kind == GRADIENT_QUADRATIC_SPHERE:
            return r * r
        if kind == GRADIENT_SPHERICAL:
            return r
    return np.zeros_like(x)


def node_tex_gradient(vector, kind=GRADIENT_LINEAR):
    """The Gradient Texture node: (n, 4), Color in [:, :3] (Fac, grey), Fac in [:, 3]."""
    f = np.clip(texture_gradient(finite(vector), kind), F(0.0), F(1.0)).astype(np.float32)
    return np.stack([f, f, f, f], -1)
