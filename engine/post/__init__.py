"""Screen-space post-process layers.

Every effect is one module here (exposing ``EFFECT``, a ``PostEffect`` subclass) plus one GLSL
file in ``shaders/post/``, with one interface: it declares its parameters as data (``Param``),
and ``execute(ctx, src, params, mix)`` returns the texture holding its result. The layer
properties and the sidebar UI are generated from the declarations, so adding an effect is one
module, one shader and one name in ``MODULES``.
"""

import importlib

from .base import Param, PostContext, PostEffect, PostStack

# Order = order of the "add layer" menu.
MODULES = ("blur", "glow", "scanlines", "vignette", "colorizer", "fisheye", "pixelate", "sepia", "noise", "lens_flare")


def _load():
    effects = {}
    for name in MODULES:
        module = importlib.import_module(f".{name}", __name__)
        effects[module.EFFECT.id] = module.EFFECT
    return effects


EFFECTS = _load()

__all__ = ["EFFECTS", "MODULES", "Param", "PostContext", "PostEffect", "PostStack"]
