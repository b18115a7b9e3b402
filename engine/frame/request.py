"""What a frame is asked for and what every stage of it reads.

``FrameRequest`` is what the engine asks of ``Renderer.render``: one value, made by the caller
(``render_engine``: a final render's sample range, the viewport's refinement). ``GpuCaches``
is what the renderer keeps between frames on the GPU (programs, material blocks, images,
batches, the texture pool), handed to the stages as one object. ``FramePlan`` (``renderer``)
holds both for the frame's stages, with the frame's clock and statistics: a stage is
``(frame, sample)`` and a new input of the frame is one field of ``FrameRequest``.
"""

import dataclasses


@dataclasses.dataclass(frozen=True)
class FrameRequest:
    """One frame as the engine asks for it.

    ``camera``: the ``extract.Camera`` it is seen through; ``settings``: the render settings
    view (``properties.RenderSettings``); ``width``/``height``: its pixels; ``aux``: also the
    depth, shadow and normal targets (a final render's passes); ``samples``: the range of
    sample indices this call draws (a start of 0 begins the frame afresh) of a frame of
    ``sample_count`` samples; ``emission`` (with ``aux``): the Emission pass too;
    ``adaptive`` (``sampling.Adaptive``): what may end the frame early; ``deadline`` (a
    ``sampling.clock()`` value): when its time limit ends it, if not counted from this call's
    first sample; ``navigating``: a one-sample frame while the view moves; ``motion``
    (``motion.Motion``): what moves during the shutter; ``passes``: Blender's further passes
    the view layer asks for (``features/passes.py`` keys: data, colour, AOV, Cryptomatte);
    ``cryptomatte``: with Cryptomatte, its levels and the kinds asked (indices into
    ``cryptomatte.KINDS``)."""

    camera: object
    settings: object
    width: int
    height: int
    aux: bool = True
    samples: tuple = (0, 1)
    sample_count: int = 1
    emission: bool = False
    adaptive: object = None
    deadline: float | None = None
    navigating: bool = False
    motion: object = None
    passes: tuple = ()
    cryptomatte: tuple = (6, (0, 1, 2))

    @property
    def size(self):
        return (self.width, self.height)

    @property
    def accumulate(self):
        """The frame has several samples, averaged in the film."""
        return self.sample_count > 1


@dataclasses.dataclass
class GpuCaches:
    """What a renderer keeps on the GPU between frames, passed to its stages as one object:
    ``shaders`` (``loader.ShaderCache``: compiled programs), ``materials``
    (``material_blocks.MaterialBlocks``), ``textures`` (``textures.TextureCache``: images),
    ``batches`` (``batches.Batches``: meshes' vertex data) and ``pool`` (``gpu_pool.TexturePool``
    of final renders, or None)."""

    shaders: object
    materials: object
    textures: object
    batches: object
    pool: object = None

    @classmethod
    def create(cls, pool=None, shaders=None, store=None):
        """Fresh caches (inside a GPU context); ``shaders``: a ``ShaderCache`` shared with
        other renderers (final renders), else one of their own; ``store``: the extension's
        ``store.Store`` batches are also kept in between renders (final renders), or None."""
        from ...shaders.loader import ShaderCache
        from ..scene.textures import TextureCache
        from .batches import Batches
        from .material_blocks import MaterialBlocks

        shaders = shaders if shaders is not None else ShaderCache()
        return cls(shaders, MaterialBlocks(), TextureCache(store), Batches(store), pool)

    @property
    def uploaded(self):
        """Bytes the material blocks and batches have sent to the GPU."""
        return self.materials.uploaded + self.batches.uploaded
