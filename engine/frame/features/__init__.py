"""The frame's techniques, one module each, over the same small set of hooks (``Feature``).

A technique that a frame may or may not need (the world's ratio estimator, the world's image in
glossy lobes, a Plane probe's reflection, the scene's reflections, refraction, settling, the
diffuse bounce, the world's occlusion, depth of field, motion blur, subsurface scattering,
volumes) lives in one
module here and is registered in ``REGISTRY``. The renderer asks each registered technique whether the frame needs it
(``wanted``) and then calls the hooks of those that answered yes, in registry order, at fixed
points of the frame; it does not name them. The lit pass, the frame data and the film take what
the hooks return (``LitPart``: fields of the lit program's variant, rows of the frame block,
samplers; ``film``: the film's targets). A technique left out of ``REGISTRY`` is off: the frame
renders without it. ``docs/design.md`` says how a new technique joins.
"""

from .base import NO_PART, Feature, LitPart
from .bounce import Bounce
from .cubes import CubeReflections
from .depth_of_field import DepthOfField
from .motion_blur import MotionBlur
from .passes import Passes
from .planar import PlanarReflections
from .reflections import Reflections
from .refraction import Refraction
from .settling import Settling
from .subsurface import Subsurface
from .volumes import Volumes
from .world_env import WorldEnvironment
from .world_occlusion import WorldOcclusion
from .world_ratio import WorldRatio

# The order their hooks run in: motion blur first (it moves a sample's scene and camera), then
# depth of field (the sample's point of the lens), the world's ratio (its directions), its
# image in glossy lobes (a Plane probe's capture takes it), a Plane probe's mirrored capture,
# the scene's reflections in them, the cube maps of what the screen does not hold, what
# transmissive surfaces refract, the world's occlusion
# (which keeps the first sample from the directions), the bounce, the light below subsurface
# surfaces (added to the sample's colour before the media dim it), the media's march (over the
# lit pass's z-buffer; it tells settling that its pixels change), and settling last (it
# decides over what the others planned); the passes' draws after all of them (they draw over what
# the lit pass left).
REGISTRY = (
    MotionBlur,
    DepthOfField,
    WorldRatio,
    WorldEnvironment,
    PlanarReflections,
    Reflections,
    CubeReflections,
    Refraction,
    WorldOcclusion,
    Bounce,
    Subsurface,
    Volumes,
    Settling,
    Passes,
)

__all__ = ["NO_PART", "REGISTRY", "Feature", "LitPart"]
