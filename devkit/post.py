"""Post-stack helpers shared by the tests and the tools: layers built from the effects' own
declarations, the stack run on an image inside a GPU context, and test images.

A layer is only ever built by ``make_layer`` (through ``layer``), so the layer record's shape
lives in one place. Nothing here imports Blender or the ``penumbra`` package at import time:
the package is loaded on first use (``session.load_penumbra``), and ``gpu`` is imported inside
the jobs that run in a GPU context.
"""

import numpy as np

# A parameter value standing for "as large as a user can type" where a ``Param`` declares no
# upper bound at all (neither ``max`` nor ``soft_max``), and its negative where it declares no
# ``min``. INT properties are 32-bit in Blender.
LARGE_FLOAT = 3.4028234663852886e38  # float32 max: the largest value a FloatProperty takes
HDR_PIXEL = 1.0e6  # a very bright but real HDR pixel (images the user picks for a layer)
LARGE_INT = 2**31 - 1


# --- layers ----------------------------------------------------------------------------------


def effects():
    """{effect id: PostEffect subclass}: the registered effects of the loaded package."""
    from .session import load_penumbra

    load_penumbra()
    from penumbra.engine.post import EFFECTS

    return EFFECTS


def effect_ids():
    """The registered effect ids, in registry order."""
    return list(effects())


def make_layer(effect_id, enabled, mix, params):
    """The stack's layer record, ``penumbra.engine.post.Layer`` (effect, enabled, mix, params)."""
    from penumbra.engine.post import Layer

    return Layer(effect_id, enabled, mix, params)


def layer(effect_id, mix=1.0, enabled=True, **params):
    """A layer of ``effect_id`` with its declared defaults, overridden by keyword. An unknown
    effect id or parameter name raises (never silently ignored)."""
    registry = effects()
    if effect_id not in registry:
        raise ValueError(f"unknown post effect {effect_id!r}; expected one of {', '.join(registry)}")
    values = registry[effect_id].defaults()
    declared = vars(values)
    unknown = sorted(set(params) - set(declared))
    if unknown:
        raise TypeError(f"{effect_id} has no parameter {', '.join(unknown)}; it has {', '.join(declared)}")
    for name, value in params.items():
        setattr(values, name, value)
    return make_layer(effect_id, enabled, mix, values)


def param_extremes(param):
    """The values of one ``Param`` a contract test pushes it to: its declared bounds (``max``,
    else ``soft_max``; plus a large value where no hard ``max`` exists, since the property
    accepts it), every item of an ENUM, both BOOLs. [(label, value)]; IMAGE parameters
    are handled by the caller (they need Blender images)."""
    kind = param.type
    if kind == "BOOL":
        return [("False", False), ("True", True)]
    if kind == "ENUM":
        return [(item[0], item[0]) for item in param.items]
    if kind == "COLOR":  # the property's range is [0, inf)
        n = len(param.default)
        return [("0", (0.0,) * n), (f"{LARGE_FLOAT:g}", (LARGE_FLOAT,) * n)]
    if kind not in ("FLOAT", "INT"):
        return []
    cast, large = (float, LARGE_FLOAT) if kind == "FLOAT" else (int, LARGE_INT)
    values = [cast(param.min) if param.min is not None else -large]
    if param.max is not None:
        values.append(cast(param.max))
    else:
        if getattr(param, "soft_max", None) is not None:
            values.append(cast(param.soft_max))
        values.append(large)
    out = []
    for v in values:
        if all(v != seen for _, seen in out):
            out.append((f"{v:g}" if kind == "FLOAT" else str(v), v))
    return out


# --- running the stack -----------------------------------------------------------------------


def _reset_scene():
    """A fresh file with a camera (a GPU call renders the current scene)."""
    from . import scenes

    scenes.top_camera(scenes.empty_scene(8, 8))


def run_many(gpu_call, runs, make_runs=None):
    """Run the post stack once per ``(image, layers, frame)`` in ``runs`` inside one GPU call, a
    fresh context and stack each time; returns [(array (h, w, 4), FrameStats)].

    ``make_runs()``, when given, builds the runs after the file is reset (for layers that
    reference Blender images)."""

    def job(engine, depsgraph):
        import gpu

        from penumbra.engine.frame.film import texture_array
        from penumbra.engine.frame.stats import FrameStats
        from penumbra.engine.post import PostContext, post_stack
        from penumbra.shaders.loader import ShaderCache

        shaders = ShaderCache()
        uploaded = {}
        results = []
        for image, layers, frame in todo:  # ``todo`` keeps every image alive: ids are unique
            h, w = image.shape[:2]
            src = uploaded.get(id(image))
            if src is None:
                data = np.ascontiguousarray(image, np.float32).ravel()
                buf = gpu.types.Buffer("FLOAT", data.size, data.tolist())
                src = uploaded[id(image)] = gpu.types.GPUTexture((w, h), format="RGBA32F", data=buf)
            stats = FrameStats()
            ctx = PostContext(shaders, w, h, frame=frame, stats=stats)
            out = post_stack().run(ctx, src, layers)
            results.append((texture_array(out, 4).copy(), stats))
        return results

    _reset_scene()
    todo = [(img, list(layers), frame) for img, layers, frame in (make_runs() if make_runs is not None else runs)]
    return gpu_call(job)


def run_stack(gpu_call, image, layers=None, frames=(0,), make_layers=None):
    """Upload ``image`` (h, w, 4 float32) and run the post stack on it once per frame number
    in ``frames`` (fresh context and stack each time); returns [(array, FrameStats)].

    ``make_layers()``, when given, builds the layers after the file is reset (for layers that
    reference Blender images)."""
    if make_layers is not None:
        return run_many(gpu_call, None, lambda: [(image, make_layers(), f) for f in frames])
    return run_many(gpu_call, [(image, layers, f) for f in frames])


def run_layers(gpu_call, image, layers):
    """``run_stack`` for one frame: (array, FrameStats)."""
    return run_stack(gpu_call, image, layers)[0]


def run_flat(gpu_call, width, height, color, stacks, step=60):
    """Each of ``stacks`` (lists of layers) on a ``width`` x ``height`` frame of one ``color``,
    inside one GPU call. The source is cleared on the GPU (no upload) and only every ``step``-th
    row and column of each result is read back (row by row through a framebuffer), so 8K frames
    stay cheap. Returns [(sampled array (ceil(h/step), ceil(w/step), 4), FrameStats)]."""

    def job(engine, depsgraph):
        import gpu

        from penumbra.engine.frame.film import buffer_array
        from penumbra.engine.frame.stats import FrameStats
        from penumbra.engine.post import PostContext, post_stack
        from penumbra.shaders.loader import ShaderCache

        src = gpu.types.GPUTexture((width, height), format="RGBA32F")
        src.clear(format="FLOAT", value=tuple(float(c) for c in color))
        ctx = PostContext(ShaderCache(), width, height)  # one pool of targets, as the renderer keeps
        results = []
        for layers in stacks:
            stats = ctx.stats = FrameStats()
            out = post_stack().run(ctx, src, layers)
            fb = gpu.types.GPUFrameBuffer(color_slots=(out,))
            rows = []
            with fb.bind():
                gpu.state.viewport_set(0, 0, width, height)  # read_color checks against it
                for y in range(0, height, step):
                    row = buffer_array(fb.read_color(0, y, width, 1, 4, 0, "FLOAT"))
                    rows.append(np.asarray(row, np.float32).reshape(width, 4)[::step])
            results.append((np.stack(rows), stats))
        return results

    _reset_scene()
    stacks = [list(s) for s in stacks]
    return gpu_call(job)


# --- images ----------------------------------------------------------------------------------


def hdr_image(h, w, seed, highlights=6):
    """Random colours in [0, 1.5) with a few HDR highlights (up to 40) and alpha in [0, 1)."""
    rng = np.random.default_rng(seed)
    img = rng.uniform(0.0, 1.5, (h, w, 4)).astype(np.float32)
    img[..., 3] = rng.uniform(0.0, 1.0, (h, w))
    for _ in range(highlights):
        y, x = rng.integers(0, h), rng.integers(0, w)
        img[y, x, :3] = rng.uniform(5.0, 40.0, 3)
    return img


def with_non_finite(img, seed=0, count=6):
    """A copy of ``img`` with NaN, +Inf and -Inf written into ``count`` pixels each (whole
    pixels and single components, alpha included)."""
    rng = np.random.default_rng(seed)
    out = np.array(img, np.float32, copy=True)
    h, w = out.shape[:2]
    for i, value in enumerate((np.nan, np.inf, -np.inf) * count):
        y, x = rng.integers(0, h), rng.integers(0, w)
        if i % 2:
            out[y, x] = value
        else:
            out[y, x, rng.integers(0, 4)] = value
    return out


def flare_scene(seed=0):
    """48 x 64: a dim background with a few HDR lights (one a 3 x 3 spot)."""
    rng = np.random.default_rng(seed)
    img = rng.uniform(0, 0.8, (48, 64, 4)).astype(np.float32)
    img[30, 41, :3] = (60.0, 40.0, 20.0)
    img[10:13, 12:15, :3] = 8.0
    img[20, 30, :3] = (1.5, 3.0, 0.5)
    return img


def pixel_centres(h, w):
    """(x, y) pixel-centre coordinates of an h x w image, row 0 at the bottom."""
    y, x = np.mgrid[0:h, 0:w] + 0.5
    return x, y


def coordinate_image(h, w):
    """R, G = the pixel centre's x, y: the output then shows which position it read."""
    x, y = pixel_centres(h, w)
    return np.stack([x, y, np.zeros_like(x), np.ones_like(x)], -1).astype(np.float32)


def blender_image(name, rgba):
    """A float Blender image holding ``rgba`` (h, w, 4), row 0 at the bottom, read at full
    float precision (no half-float GPU copy)."""
    import bpy

    h, w = rgba.shape[:2]
    img = bpy.data.images.new(name, w, h, float_buffer=True)
    img.use_half_precision = False
    img.pixels.foreach_set(np.ascontiguousarray(rgba, np.float32).ravel())
    return img
