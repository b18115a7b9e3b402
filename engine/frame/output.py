"""Which pixels and views a final render writes, by Blender's own rules. No bpy, no gpu."""

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Window:
    """The pixels of the full frame a render result holds: columns [x0, x1), rows [y0, y1),
    row 0 at the bottom (Blender's and the GPU's orientation)."""

    x0: int
    y0: int
    x1: int
    y1: int

    @property
    def width(self):
        return self.x1 - self.x0

    @property
    def height(self):
        return self.y1 - self.y0

    def cut(self, image):
        """The window of a full-frame array (height, width, ...)."""
        return image[self.y0 : self.y1, self.x0 : self.x1]


def render_window(width, height, use_border=False, border=(0.0, 0.0, 1.0, 1.0)):
    """The window Blender asks an engine to fill for a ``width`` x ``height`` frame (already
    scaled by the resolution %). With a render region, ``border`` = (min x, min y, max x,
    max y) as fractions; Blender truncates each edge's float32 position to whole pixels."""
    if not use_border:
        return Window(0, 0, width, height)
    f = np.float32
    xmin, ymin, xmax, ymax = border
    x0, x1 = int(f(xmin) * f(width)), int(f(xmax) * f(width))
    y0, y1 = int(f(ymin) * f(height)), int(f(ymax) * f(height))
    return Window(x0, y0, x1, y1)


def viewport_window(width, height, use_border, border, frame=None):
    """The pixels of a ``width`` x ``height`` viewport region a render region leaves visible
    (a ``Window``; the whole region without one; None when it is empty). ``border`` = (min x,
    min y, max x, max y) as fractions of ``frame``, the camera frame's (x0, y0, x1, y1) in
    region pixels in camera view (the scene's Render Region), else of the region itself (the
    viewport's own Render Region, Ctrl+B)."""
    if not use_border:
        return Window(0, 0, width, height)
    fx0, fy0, fx1, fy1 = frame if frame is not None else (0.0, 0.0, float(width), float(height))
    xmin, ymin, xmax, ymax = border
    x0 = max(0, min(width, round(fx0 + xmin * (fx1 - fx0))))
    x1 = max(0, min(width, round(fx0 + xmax * (fx1 - fx0))))
    y0 = max(0, min(height, round(fy0 + ymin * (fy1 - fy0))))
    y1 = max(0, min(height, round(fy0 + ymax * (fy1 - fy0))))
    return Window(x0, y0, x1, y1) if x1 > x0 and y1 > y0 else None


def frame_in_region(corners, perspective_matrix, width, height):
    """The region-pixel rectangle (x0, y0, x1, y1) around world points ``corners`` (the
    camera frame's) seen through a viewport's ``perspective_matrix``; None when one is behind
    the view."""
    pts = np.asarray(corners, np.float64)
    clip = np.c_[pts, np.ones(len(pts))] @ np.asarray(perspective_matrix, np.float64).T
    if not np.all(clip[:, 3] > 0.0):
        return None
    x = (clip[:, 0] / clip[:, 3] * 0.5 + 0.5) * width
    y = (clip[:, 1] / clip[:, 3] * 0.5 + 0.5) * height
    return float(x.min()), float(y.min()), float(x.max()), float(y.max())


def scaled_size(resolution_x, resolution_y, percentage):
    """Blender's integer resolution rule: ``resolution * percentage / 100``, truncated."""
    return max(1, resolution_x * percentage // 100), max(1, resolution_y * percentage // 100)


def render_views(render):
    """The view names a render writes: ``[""]`` for a mono render; with multiview, the left and
    right eye (Stereo 3D) or every view switched on (Multi-View), as Blender renders them."""
    if not render.use_multiview:
        return [""]
    if render.views_format == "STEREO_3D":
        return [v.name for v in render.views if v.name in ("left", "right")]
    return [v.name for v in render.views if v.use]


# Blender settings a scene can switch on that Penumbra does not render: (where, attribute,
# what the user is told[, the value that is not rendered: True unless given]). Checked on every
# final render; each one in use is named once in the render report.
_UNSUPPORTED = (
    ("camera", "type", "panoramic cameras are not rendered (drawn as a perspective camera)", "PANO"),
    ("render", "use_freestyle", "Freestyle lines are not rendered"),
)


def _lookup(owner, path):
    for part in path.split("."):
        owner = getattr(owner, part, None)
        if owner is None:
            return None
    return owner


# Blender's further passes Penumbra writes (``features/passes.py``): the view layer's switch,
# the pass's key, its name from Blender 5.0 and before it, channels, chan_id, type.
FURTHER_PASSES = (
    ("use_pass_position", "POSITION", "Position", "Position", 3, "XYZ", "VECTOR"),
    ("use_pass_object_index", "OBJECT_INDEX", "Object Index", "IndexOB", 1, "X", "VALUE"),
    ("use_pass_material_index", "MATERIAL_INDEX", "Material Index", "IndexMA", 1, "X", "VALUE"),
    ("use_pass_diffuse_color", "DIFFUSE_COLOR", "Diffuse Color", "DiffCol", 3, "RGB", "COLOR"),
    ("use_pass_glossy_color", "GLOSSY_COLOR", "Glossy Color", "GlossCol", 3, "RGB", "COLOR"),
    ("use_pass_transmission_color", "TRANSMISSION_COLOR", "Transmission Color", "TransCol", 3, "RGB", "COLOR"),
    ("use_pass_environment", "ENVIRONMENT", "Environment", "Env", 3, "RGB", "COLOR"),
    ("use_pass_diffuse_direct", "DIFFUSE_DIRECT", "Diffuse Direct", "DiffDir", 3, "RGB", "COLOR"),
    ("use_pass_diffuse_indirect", "DIFFUSE_INDIRECT", "Diffuse Indirect", "DiffInd", 3, "RGB", "COLOR"),
    ("use_pass_glossy_direct", "GLOSSY_DIRECT", "Glossy Direct", "GlossDir", 3, "RGB", "COLOR"),
    ("use_pass_glossy_indirect", "GLOSSY_INDIRECT", "Glossy Indirect", "GlossInd", 3, "RGB", "COLOR"),
    ("use_pass_transmission_direct", "TRANSMISSION_DIRECT", "Transmission Direct", "TransDir", 3, "RGB", "COLOR"),
    ("use_pass_vector", "VECTOR", "Vector", "Vector", 4, "XYZW", "VECTOR"),
    ("use_pass_uv", "UV", "UV", "UV", 3, "UVA", "VECTOR"),
)
# What the GPU draws for a pass computed from others on the CPU (``vectors.py``).
DRAWN_FOR = {"VECTOR": ("POSITION", "DRAW")}


def drawn_passes(keys):
    """The ``FrameRequest.passes`` of asked ``keys``: each, or what it is computed from."""
    out = []
    for key in keys:
        out += DRAWN_FOR.get(key, (key,))
    return tuple(dict.fromkeys(out))


# The Color pass each light pass is divided by (Cycles: Direct = light / Color where Color is
# not 0, else 0), so that Direct x Color is the light the surface reflects.
LIGHT_COLOR = {
    "DIFFUSE_DIRECT": "DIFFUSE_COLOR",
    "DIFFUSE_INDIRECT": "DIFFUSE_COLOR",
    "GLOSSY_DIRECT": "GLOSSY_COLOR",
    "GLOSSY_INDIRECT": "GLOSSY_COLOR",
    "TRANSMISSION_DIRECT": "TRANSMISSION_COLOR",
}


def divided(light, color):
    """A light pass over its Color pass, channel by channel; 0 where the colour is 0."""
    light, color = np.asarray(light, np.float64), np.asarray(color, np.float64)
    out = np.divide(light, color, out=np.zeros_like(light), where=color > 0.0)
    return out.astype(np.float32)


# Penumbra's Denoising Data switch (``penumbra.use_pass_denoising``): Cycles' names.
DENOISING_PASSES = (
    ("DENOISING_ALBEDO", "Denoising Albedo", 3, "RGB", "COLOR"),
    ("DENOISING_NORMAL", "Denoising Normal", 3, "XYZ", "VECTOR"),
)
CRYPTOMATTE_SWITCHES = ("use_pass_cryptomatte_object", "use_pass_cryptomatte_material", "use_pass_cryptomatte_asset")

# The view layer passes Penumbra writes (its own Shadow and Lit passes live in ``penumbra``).
WRITTEN_PASSES = {
    "use_pass_combined",
    "use_pass_z",
    "use_pass_normal",
    "use_pass_mist",
    "use_pass_emit",
    *(p[0] for p in FURTHER_PASSES),
    *CRYPTOMATTE_SWITCHES,
}


def pass_name(further, new_names):
    """A ``FURTHER_PASSES`` row's pass name on this Blender line (``new_names``: 5.0 and later)."""
    return further[2] if new_names else further[3]


def cryptomatte_levels(view_layer):
    """The view layer's Cryptomatte levels, at most 16 (Blender's and Cycles' bound)."""
    return min(16, max(1, int(getattr(view_layer, "pass_cryptomatte_depth", 6))))


def requested_passes(view_layer):
    """The ``FrameRequest.passes`` keys of what ``view_layer`` asks for beyond Combined, Depth,
    Mist, Normal, Emission and Penumbra's own: its switched-on ``FURTHER_PASSES``, Penumbra's
    Denoising Data, its valid Shader AOVs, its light groups and Cryptomatte."""
    keys = [p[1] for p in FURTHER_PASSES if getattr(view_layer, p[0], False) is True]
    own = getattr(view_layer, "penumbra", None)
    if own is not None and getattr(own, "use_pass_denoising", False):
        keys += [p[0] for p in DENOISING_PASSES]
    for aov in getattr(view_layer, "aovs", ()):
        if aov.is_valid and aov.name:
            keys.append(f"AOV_{'VALUE' if aov.type == 'VALUE' else 'COLOR'}:{aov.name}")
    for group in getattr(view_layer, "lightgroups", ()):
        if group.name:
            keys.append(f"LIGHTGROUP:{group.name}")
    if any(getattr(view_layer, s, False) is True for s in CRYPTOMATTE_SWITCHES):
        keys.append("CRYPTOMATTE")
    return tuple(dict.fromkeys(keys))


def unsupported_in_use(camera_data, render, view_layer):
    """Messages for the settings of ``_UNSUPPORTED`` that are switched on, and for every pass of
    the view layer that is switched on but not written (a file set up for another engine keeps
    its passes switched on), AOVs and light groups included; each once."""
    owners = {"camera": camera_data, "render": render, "view_layer": view_layer}
    out = []
    for where, path, message, *value in _UNSUPPORTED:
        if _lookup(owners[where], path) == (value[0] if value else True):
            out.append(f"Penumbra: {message}")
    if view_layer is not None:
        for prop in view_layer.bl_rna.properties:
            name = prop.identifier
            if name.startswith("use_pass_") and name not in WRITTEN_PASSES and name != "use_pass_cryptomatte_accurate":
                if getattr(view_layer, name, False) is True:
                    own = " (switch on Penumbra's own in View Layer > Passes)" if name == "use_pass_shadow" else ""
                    out.append(f"Penumbra: Blender's {prop.name} pass is not written{own}")
    return list(dict.fromkeys(out))


def view_distance_scale(projection, is_ortho, width, height):
    """Per pixel (height, width), distance from the camera over distance along its axis: 1
    everywhere for an orthographic camera, ``|ray| / |ray.z|`` through each pixel centre for
    a perspective one (``projection``: the 4x4 camera projection)."""
    if is_ortho:
        return np.ones((height, width))
    xs = (np.arange(width) + 0.5) / width * 2.0 - 1.0
    ys = (np.arange(height) + 0.5) / height * 2.0 - 1.0
    ndc = np.stack(np.broadcast_arrays(xs[None, :], ys[:, None], np.full((height, width), 1.0), 1.0), -1)
    view = ndc @ np.linalg.inv(np.asarray(projection, np.float64)).T
    d = view[..., :3] / view[..., 3:4]
    return np.linalg.norm(d, axis=-1) / np.abs(d[..., 2])


MIST_FALLOFF = {
    "LINEAR": lambda m: m,
    "QUADRATIC": lambda m: m * m,
    "INVERSE_QUADRATIC": np.sqrt,
}


def mist_pass(axial_depth, distance_scale, start, depth, falloff):
    """Blender's Mist pass: 0 at ``start`` metres from the camera, 1 at ``start + depth`` and
    beyond (the background too), shaped by the world's mist ``falloff``."""
    distance = np.asarray(axial_depth, np.float64) * distance_scale
    m = np.clip((distance - start) / max(depth, 1e-12), 0.0, 1.0)
    m = np.where(np.isfinite(distance), m, 1.0)
    return MIST_FALLOFF[falloff](m).astype(np.float32)
