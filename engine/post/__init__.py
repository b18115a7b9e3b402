"""Screen-space post-process layers.

Every effect is one module here (a ``PostEffect`` subclass declaring its parameters as
``settings.Param`` rows, its numpy reference beside it) plus one GLSL file in
``shaders/post/``. Layer properties, the sidebar UI, presets and the contract tests are
generated from the registry below: adding an effect is one module, one shader and one row.
"""

from ..enums import Enum
from . import blur, colorizer, fisheye, glow, lens_flare, noise, pixelate, scanlines, sepia, vignette
from .base import Layer, PostContext, PostEffect, PostStack

# (stored number, effect). The number is what a .blend saves for a layer's effect: never
# reuse or change one. Order = order of the "add layer" menu.
REGISTRY = (
    (0, blur.Blur),
    (1, glow.Glow),
    (2, scanlines.Scanlines),
    (3, vignette.Vignette),
    (4, colorizer.Colorizer),
    (5, fisheye.Fisheye),
    (6, pixelate.Pixelate),
    (7, sepia.Sepia),
    (8, noise.Noise),
    (9, lens_flare.LensFlare),
)

EFFECTS = {cls.id: cls for _number, cls in REGISTRY}

EFFECT_ENUM = Enum(
    "post effect",
    "EFFECT",
    tuple((cls.id, cls.label, cls.description, number, cls.icon) for number, cls in REGISTRY),
)


def post_stack():
    """A PostStack over the registered effects."""
    return PostStack(EFFECTS)


__all__ = ["EFFECTS", "EFFECT_ENUM", "REGISTRY", "Layer", "PostContext", "PostEffect", "PostStack", "post_stack"]
