"""Screen-space post-process layers.

Every effect is one module here plus one GLSL file in ``shaders/post/``, with one interface:
it declares its parameters as data (``Param``), and ``execute(ctx, src, params, mix)`` returns
the texture holding its result. The layer properties and the sidebar UI are generated from
the declarations (see ``properties.py`` and ``ui/``), so adding an effect needs no other code.
"""

from . import blur, vignette
from .base import Param, PostContext, PostEffect, PostStack

# Order = order of the "add layer" menu.
EFFECTS = {cls.id: cls for cls in (blur.Blur, vignette.Vignette)}

__all__ = ["EFFECTS", "Param", "PostContext", "PostEffect", "PostStack"]
