"""Debug views (``scene.penumbra.debug_view``): where a frame's quality and time went, shown
instead of its image in the viewport and the final render.

Each view shows numbers the engine itself used for the frame, not a second computation:

* SHADOW_MAPS: the shadow atlas as the last sample drew it (its depths read back), each map
  outlined where planning placed it and labelled with its light, cube face or cascade and size;
* TEXEL_DENSITY, CASCADES, LIGHT_COST: written by the lit pass itself (its ``DEBUG_LIT``
  variant) as it evaluates the lights: texels per pixel of the worst-sampled light at the
  lookup it made, the cascade it picked, the lights it evaluated; averaged over the frame's
  samples like colour;
* SAMPLES: the samples each pixel was shaded in (its accumulated weight against the running
  totals of the samples' weights: ``Film.samples_array``);
* NOISE: the error estimate of adaptive sampling's check (``Film.error_array``), in units of
  the Noise Threshold;
* WORLD_LIGHT, INDIRECT: the world's light alone (with its visibility) and the diffuse bounce
  alone, in colour: the lit pass's ``DEBUG_TERM`` variant writes that term of its colour; so do
  COAT_LIGHT and SHEEN_LIGHT (a Principled coat's reflection, a sheen's light, each alone);
  VOLUME_LIGHT and SUBSURFACE_LIGHT write nothing there, and the media's march or the
  subsurface diffusion adds its light alone.
* WORLD_AO: the world's visibility from the ambient occlusion (``world/occlusion.py``), written by the
  lit pass's ``DEBUG_LIT`` variant with ``WORLD_AO`` (every sample occluded), in grey.
* REFLECTIONS: where the reflections' rays met the scene (``features/reflections.py``: the
  weight of the pixel's surest hit, 0 where none), written by the ``DEBUG_LIT`` variant with
  ``DEBUG_REFLECTIONS`` (every sample traces), in grey.

``DebugImage.values`` holds those numbers per pixel (tests read them); ``image`` is what is
shown: the values through a colour scale with a legend strip along the bottom, ``legend`` says
in words what the colours mean (the viewport's text and the render report).
"""

from dataclasses import dataclass, field

import numpy as np

from ..enums import DEBUG_VIEW

# Colour scales as (position, linear RGB) stops.
HEAT = ((0.0, (0.0, 0.0, 0.02)), (0.3, (0.25, 0.02, 0.35)), (0.6, (0.9, 0.2, 0.05)), (1.0, (1.0, 0.95, 0.5)))
CASCADE_COLORS = np.array([(0.9, 0.1, 0.1), (0.1, 0.8, 0.1), (0.15, 0.3, 1.0), (0.95, 0.85, 0.1)], np.float32)
NO_DATA = (0.18, 0.18, 0.18)  # a surface the view has no number for (no map, no cascaded sun)
BACKGROUND = (0.0, 0.0, 0.0)
ATLAS_EMPTY = (0.02, 0.03, 0.08)  # atlas texels no map uses
DENSITY_RANGE = 3.0  # the density scale spans 2^-3 .. 2^3 texels per pixel
NOISE_RANGE = 10.0  # the noise scale spans 0 .. 10x the Noise Threshold
FACE_NAMES = ("+X", "-X", "+Y", "-Y", "+Z", "-Z")  # cube faces in shadow_filters.glsl cube_face order


@dataclass
class DebugImage:
    view: str
    values: np.ndarray  # (height, width) float32: the numbers shown, row 0 at the bottom
    image: np.ndarray  # (height, width, 4) float32 linear RGBA shown
    legend: str
    covered: np.ndarray  # (height, width) bool: pixels the values are defined at
    tiles: list = field(default_factory=list)  # SHADOW_MAPS: (x0, y0, x1, y1) frame pixels, label
    labels: list = field(default_factory=list)  # (x, top y, text, widest) drawn over the image
    scale: tuple = (0.0, 1.0)  # the values at the legend strip's ends


def _ramp(t, stops):
    """Colours of ``t`` in [0, 1] along ``stops``."""
    t = np.clip(np.nan_to_num(t, nan=0.0), 0.0, 1.0)
    xs = [s[0] for s in stops]
    return np.stack([np.interp(t, xs, [s[1][c] for s in stops]) for c in range(3)], axis=-1)


def _density_color(d):
    """Texels per pixel: red below 1 (undersampled), green at 1, blue above (wasted), on a log
    scale saturating at 2^-3 and 2^3."""
    t = np.clip(np.log2(np.maximum(d, 1e-30)) / DENSITY_RANGE, -1.0, 1.0)
    green = np.array([0.1, 0.85, 0.1])
    red = np.array([0.95, 0.05, 0.05])
    blue = np.array([0.1, 0.2, 1.0])
    under = np.clip(-t, 0.0, 1.0)[..., None]
    over = np.clip(t, 0.0, 1.0)[..., None]
    return green * (1.0 - under - over) + red * under + blue * over


def _cascade_color(c):
    """A cascade index (fractional where samples picked two cascades in a blend band)."""
    c = np.clip(c, 0.0, 3.0)
    lo = np.floor(c).astype(int)
    hi = np.minimum(lo + 1, 3)
    f = (c - lo)[..., None]
    return CASCADE_COLORS[lo] * (1.0 - f) + CASCADE_COLORS[hi] * f


def _noise_color(v):
    """Error estimate over the Noise Threshold: green below 1 (converged), yellow to red up to
    10x on a log scale."""
    t = np.clip(np.log10(np.maximum(v, 1.0)), 0.0, 1.0)[..., None]
    below = (v < 1.0)[..., None]
    yellow_red = np.array([1.0, 0.9, 0.1]) * (1.0 - t) + np.array([0.95, 0.05, 0.05]) * t
    return np.where(below, np.array([0.1, 0.7, 0.2]), yellow_red)


def _compose(values, covered, color_of, strip_of, special=None):
    """RGBA image of ``values`` through ``color_of`` where ``covered`` (``special``: (mask,
    colour) overrides), the background elsewhere, and along the bottom the legend strip:
    ``strip_of(t)`` for t from 0 (left) to 1 (right)."""
    height, width = values.shape
    rgb = np.empty((height, width, 3), np.float32)
    rgb[:] = BACKGROUND
    rgb[covered] = color_of(values[covered])
    if special is not None:
        mask, color = special
        rgb[covered & mask] = color
    rows = max(4, min(16, height // 16))
    if rows < height // 2:
        rgb[:rows] = strip_of((np.arange(width) + 0.5) / max(width, 1))[None]
    return np.concatenate([rgb, np.ones((height, width, 1), np.float32)], axis=-1)


def lit_view(view, raw, occluded=True):
    """A lit debug view from the lit pass's ``DEBUG_LIT`` output ``raw`` (height, width, 4):
    lights evaluated, 1 + cascade, texel density, coverage; for WORLD_AO the world's
    visibility, coverage (``occluded`` False: no occlusion ran, every point sees all of it)."""
    item = DEBUG_VIEW[view]
    covered = raw[..., 3] > 0.5
    if item.term:  # WORLD_LIGHT, INDIRECT: one term of the colour, shown as colour
        rgb = np.nan_to_num(raw[..., :3]).astype(np.float32)
        image = np.concatenate([rgb, np.ones(covered.shape + (1,), np.float32)], axis=-1)
        values = (rgb @ np.array([0.2126, 0.7152, 0.0722], np.float32)).astype(np.float32)  # luminance
        return DebugImage(view, values, image, f"{item.label}: {item.legend}", covered)
    if view in ("WORLD_AO", "REFLECTIONS"):
        values = np.clip(raw[..., 0], 0.0, 1.0).astype(np.float32)
        if view == "WORLD_AO" and not occluded:
            values = np.ones(covered.shape, np.float32)
        image = _compose(
            values, covered, lambda v: np.repeat(v[..., None], 3, -1), lambda t: np.repeat(t[..., None], 3, -1)
        )
        return DebugImage(view, values, image.astype(np.float32), f"{item.label}: {item.legend}", covered)
    if view == "LIGHT_COST":
        values = raw[..., 0].astype(np.float32)
        hi = max(1.0, float(values[covered].max()) if covered.any() else 1.0)
        image = _compose(values, covered, lambda v: _ramp(v / hi, HEAT), lambda t: _ramp(t, HEAT))
        scale = (0.0, hi)
    elif view == "CASCADES":
        values = (raw[..., 1] - 1.0).astype(np.float32)  # -1: no cascaded sun looked up here
        image = _compose(
            values, covered, _cascade_color, lambda t: _cascade_color(4.0 * t - 0.5), (values < -0.5, NO_DATA)
        )
        scale = (0.0, 3.0)
    else:  # TEXEL_DENSITY
        values = raw[..., 2].astype(np.float32)  # 0: no map looked up here
        image = _compose(
            values,
            covered,
            _density_color,
            lambda t: _density_color(2.0 ** (DENSITY_RANGE * (2.0 * t - 1.0))),
            (values <= 0.0, NO_DATA),
        )
        scale = (2.0**-DENSITY_RANGE, 2.0**DENSITY_RANGE)
    legend = f"{item.label}: {item.legend}"
    return DebugImage(view, values, image.astype(np.float32), legend, covered, scale=scale)


def samples_view(samples):
    """SAMPLES from ``Film.samples_array`` (or a single-sample frame's ones)."""
    covered = np.ones(samples.shape, bool)
    hi = max(1.0, float(samples.max()))
    image = _compose(samples, covered, lambda v: _ramp(v / hi, HEAT), lambda t: _ramp(t, HEAT))
    item = DEBUG_VIEW["SAMPLES"]
    legend = f"{item.label}: {item.legend} ({int(samples.min())} to {int(hi)})"
    return DebugImage("SAMPLES", samples.astype(np.float32), image.astype(np.float32), legend, covered, scale=(0.0, hi))


def noise_view(errors, size):
    """NOISE from ``Film.error_array`` (None: the frame had one sample, nothing to estimate)."""
    item = DEBUG_VIEW["NOISE"]
    width, height = size
    if errors is None:
        values = np.zeros((height, width), np.float32)
        covered = np.zeros((height, width), bool)
        legend = f"{item.label}: no estimate: the frame has one sample (the estimate compares samples)"
    else:
        values = errors.astype(np.float32)
        covered = np.ones(values.shape, bool)
        legend = f"{item.label}: {item.legend}"
    image = _compose(values, covered, _noise_color, lambda t: _noise_color(NOISE_RANGE * t))
    return DebugImage("NOISE", values, image.astype(np.float32), legend, covered, scale=(0.0, NOISE_RANGE))


def atlas_depths(texels, depth_format):
    """Stored shadow depths in [0, 1] from the atlas texture's texels (height, width, channels)."""
    if depth_format == "RGBA8":
        return texels @ np.array([1.0, 1.0 / 255.0, 1.0 / 65025.0, 1.0 / 16581375.0], np.float32)
    return texels[..., 0]


def tile_labels(plan, lights):
    """{tile index: label} of a shadow plan: the light's name, its cube face or cascade, and the
    map's size in texels."""
    labels = {}
    for index, shadow in plan.lights.items():
        light = lights[index] if index < len(lights) else None
        name = (getattr(light, "name", "") or f"light {index}") if light is not None else f"light {index}"
        for k, tile in enumerate(shadow.tiles):
            if tile < 0 or tile >= len(plan.tiles):
                continue
            if shadow.mode == "CUBE":
                part = f" {FACE_NAMES[k]}" if k < len(FACE_NAMES) else f" face {k}"
            elif shadow.mode == "CASCADE":
                part = f" cascade {k}"
            else:
                part = ""
            labels[tile] = f"{name}{part} {plan.tiles[tile].size}"
    return labels


def shadow_maps_view(depths, plan, lights, size):
    """SHADOW_MAPS: the atlas ``depths`` (rows, columns; row 0 at the bottom) fitted into the
    frame ``size`` (letterboxed, nearest texel), each map of ``plan`` outlined and labelled."""
    width, height = size
    item = DEBUG_VIEW["SHADOW_MAPS"]
    values = np.zeros((height, width), np.float32)
    covered = np.zeros((height, width), bool)
    image = np.zeros((height, width, 4), np.float32)
    image[..., 3] = 1.0
    tiles, labels = [], []
    if depths is None or not plan.tiles:
        legend = f"{item.label}: no shadow map this frame"
        return DebugImage("SHADOW_MAPS", values, image, legend, covered)
    rows, cols = depths.shape
    scale = min(width / cols, height / rows)
    ox = 0.5 * (width - cols * scale)
    oy = 0.5 * (height - rows * scale)
    # Which atlas texel each frame pixel shows (nearest, through the pixel's centre).
    tx = np.floor((np.arange(width) + 0.5 - ox) / scale).astype(int)
    ty = np.floor((np.arange(height) + 0.5 - oy) / scale).astype(int)
    inside_x = (tx >= 0) & (tx < cols)
    inside_y = (ty >= 0) & (ty < rows)
    in_atlas = inside_y[:, None] & inside_x[None, :]
    sampled = depths[np.clip(ty, 0, rows - 1)][:, np.clip(tx, 0, cols - 1)]
    # Texels a map uses: inside some tile.
    used = np.zeros((rows, cols), bool)
    for tile in plan.tiles:
        x0, y0 = tile.origin
        used[y0 : y0 + tile.size, x0 : x0 + tile.size] = True
    in_tile = in_atlas & used[np.clip(ty, 0, rows - 1)][:, np.clip(tx, 0, cols - 1)]
    values[in_tile] = sampled[in_tile]
    covered = in_tile
    grey = np.sqrt(np.clip(values, 0.0, 1.0))  # near dark, far light (and a cleared texel white)
    image[..., :3] = grey[..., None]
    image[in_atlas & ~in_tile, :3] = ATLAS_EMPTY
    names = tile_labels(plan, lights)
    for index, tile in enumerate(plan.tiles):
        x0 = ox + tile.origin[0] * scale
        y0 = oy + tile.origin[1] * scale
        x1 = x0 + tile.size * scale
        y1 = y0 + tile.size * scale
        label = names.get(index, f"map {index} {tile.size}")
        tiles.append(((x0, y0, x1, y1), label))
        color = CASCADE_COLORS[index % len(CASCADE_COLORS)]
        _outline(image, x0, y0, x1, y1, color)
        labels.append((x0 + 3.0, y1 - 3.0, label, x1 - x0 - 6.0))
    legend = f"{item.label}: {item.legend}; " + ", ".join(label for _, label in tiles)
    return DebugImage("SHADOW_MAPS", values, image, legend, covered, tiles=tiles, labels=labels, scale=(0.0, 1.0))


def _outline(image, x0, y0, x1, y1, color):
    """A one-pixel rectangle along the inside of the frame-pixel bounds (x0, y0)-(x1, y1)."""
    height, width = image.shape[:2]
    left, right = int(np.clip(np.floor(x0 + 0.5), 0, width - 1)), int(np.clip(np.ceil(x1 - 0.5) - 1, 0, width - 1))
    bottom, top = int(np.clip(np.floor(y0 + 0.5), 0, height - 1)), int(np.clip(np.ceil(y1 - 0.5) - 1, 0, height - 1))
    image[bottom : top + 1, left, :3] = color
    image[bottom : top + 1, right, :3] = color
    image[bottom, left : right + 1, :3] = color
    image[top, left : right + 1, :3] = color


def upload(debug, pixel_scale=1.0):
    """The debug image as a GPU texture, with its labels drawn over it (Blender's font module).
    Inside the GPU context."""
    import gpu

    height, width = debug.image.shape[:2]
    data = gpu.types.Buffer("FLOAT", width * height * 4, np.ascontiguousarray(debug.image).ravel())
    texture = gpu.types.GPUTexture((width, height), format="RGBA32F", data=data)
    if debug.labels:
        _draw_labels(texture, debug.labels, pixel_scale)
    return texture


def _draw_labels(texture, labels, pixel_scale):
    import blf
    import gpu
    from mathutils import Matrix

    width, height = texture.width, texture.height
    framebuffer = gpu.types.GPUFrameBuffer(color_slots=(texture,))
    font = 0
    size = max(8, round(11 * pixel_scale))
    with framebuffer.bind():
        gpu.state.viewport_set(0, 0, width, height)
        gpu.state.blend_set("ALPHA")
        with gpu.matrix.push_pop(), gpu.matrix.push_pop_projection():
            gpu.matrix.load_identity()
            gpu.matrix.load_projection_matrix(Matrix.Identity(4))
            gpu.matrix.translate((-1.0, -1.0))
            gpu.matrix.scale((2.0 / width, 2.0 / height))
            for x, top, text, widest in labels:
                # The largest size up to ``size`` at which the label fits its width; none below 7 px.
                for px in range(size, 6, -1):
                    blf.size(font, px)
                    w, h = blf.dimensions(font, text)
                    if w <= widest:
                        break
                else:
                    continue
                for dx, dy, c in ((1, -1, (0.0, 0.0, 0.0, 1.0)), (0, 0, (1.0, 1.0, 1.0, 1.0))):
                    blf.color(font, *c)
                    blf.position(font, x + dx, top - h + dy, 0.0)
                    blf.draw(font, text)
        gpu.state.blend_set("NONE")
