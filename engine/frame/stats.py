"""What a frame did (``FrameStats``): read by tests, the benchmarks and the render report.

On a GPU a frame's pixels are nearly free and its cost is the Python that asks for them, so
a frame also says where its CPU time went (``StageClock``): each stage's CPU time on the
render thread apart from the time spent waiting for the GPU, per frame and per sample, with
the bytes it uploaded and the draw calls and triangles of each pass.
"""

import time
from contextlib import contextmanager
from dataclasses import dataclass, field


class StageClock:
    """Seconds each stage of a frame spent on the CPU (``cpu``: the render thread's CPU time,
    ``time.thread_time``: Python and the driver's work on that thread, not the time it slept
    waiting for the GPU) and waiting for the GPU (``gpu``: the stage's read-backs, and, when
    ``fence`` is set, a function that returns once the GPU has finished everything asked so
    far, the time the GPU took to finish the stage's work after its last call). A fence
    stalls the pipeline, so only the benchmarks set one (``Renderer.fence_stages``)."""

    def __init__(self, fence=None):
        self.fence = fence
        self.cpu = {}
        self.gpu = {}
        self.waited = 0.0  # seconds the fences waited outside any stage (before the first)
        self._open = None
        self._read_back = 0.0  # seconds the open stage waited in read-backs (``waiting``)

    def begin(self, name):
        """Stage ``name`` starts (``end`` closes it; stages do not nest)."""
        if self.fence is not None:
            start = time.perf_counter()
            self.fence()
            self.waited += time.perf_counter() - start
        self._open = (name, time.thread_time())
        self._read_back = 0.0

    def end(self):
        name, start = self._open
        self.cpu[name] = self.cpu.get(name, 0.0) + time.thread_time() - start
        issued = time.perf_counter()
        gpu = self._read_back
        if self.fence is not None:
            self.fence()
            gpu += time.perf_counter() - issued
        if self.fence is not None or gpu:
            self.gpu[name] = self.gpu.get(name, 0.0) + gpu
        self._read_back = 0.0

    @contextmanager
    def waiting(self):
        """A read-back inside the open stage (a count of converged pixels, the centred
        sample's depth): its wall time counts as the stage's GPU time."""
        start = time.perf_counter()
        try:
            yield
        finally:
            self._read_back += time.perf_counter() - start

    @contextmanager
    def stage(self, name):
        self.begin(name)
        try:
            yield
        finally:
            self.end()

    @property
    def cpu_seconds(self):
        return sum(self.cpu.values())

    @property
    def gpu_seconds(self):
        return sum(self.gpu.values())


@dataclass
class FrameStats:
    """What a frame did: read by tests and the benchmark ("model only what a scene requires")."""

    shadow_maps: int = 0  # maps drawn this frame
    shadow_maps_reused: int = 0  # maps whose fit and casters did not change: not redrawn
    shadow_texels: int = 0  # texels of the maps drawn (each its size squared: the depth pass's fill)
    shadow_triangles: int = 0  # triangles drawn into the maps drawn (each map counts its casters')
    shadow_simplified: int = 0  # casters drawn into a map at its texel footprint (``shadow_pass.map_levels``)
    passes: int = 0
    post_passes: int = 0
    post_layers: int = 0  # post layers drawn (consecutive point layers share one pass)
    draws: int = 0
    triangles: int = 0
    texture_bytes: int = 0
    shadow_bytes: int = 0  # the shadow atlas (and its one-tile scratch target, if any)
    shaders_compiled: int = 0
    compile_seconds: float = 0.0  # spent compiling those programs (compiled node trees included)
    samples: int = 0  # samples rendered by this call
    lights_sampled: int = 0  # lights that moved between samples (the others kept one map)
    world_directions: int = 0  # directions of the world's light drawn with shadow maps (world/directions.py)
    lens_reach: float = 0.0  # depth of field: the widest circle of confusion's radius, pixels (frame/lens.py)
    cancelled: bool = False  # on_sample asked to stop before the last sample
    stopped: str = ""  # why the frame ended before its last sample: "converged" or "time limit"
    pixels_converged: int = 0  # pixels adaptive sampling stopped (Noise Threshold)
    pixels_settled: int = 0  # of those, pixels settled after the first sample(s) (``features/settling.py``)
    pixel_samples_skipped: int = 0  # of the samples taken, those converged pixels were not shaded in (summed)
    lights_out_of_view: int = 0  # lights that reach no visible surface: no map, no shading
    closed_culled: int = 0  # closed instances drawn without back faces (lit pass and each map)
    simplified: int = 0  # instances drawn at a level of detail (``simplify``; ``triangles`` counts its)
    debug_legend: str = ""  # a debug view's legend: what its colours mean (``debug_view``)
    binned: bool = False  # the lit pass looped over each screen bin's lights only
    shadow_draws: int = 0  # of ``draws``, the draw calls into shadow maps
    # Camera depth prepasses drawn for the world's ambient occlusion (``world_ao``) and their
    # draw calls; counted apart, not in ``passes`` and ``draws``.
    ao_prepasses: int = 0
    ao_draws: int = 0
    # Reflections (``features/reflections.py``): camera depth prepasses drawn for the traced
    # rays (counted apart, as the occlusion's), and samples that traced.
    reflection_prepasses: int = 0
    reflection_samples: int = 0
    planar_captures: int = 0  # lit passes drawn mirrored about a Plane Light Probe
    cube_faces: int = 0  # lit passes drawn into cube maps (``features/cubes.py``: six a cube)
    # Refraction (``features/refraction.py``): camera depth prepasses of what is not
    # transmissive, and samples that copied the colour transmissive surfaces see through.
    refraction_prepasses: int = 0
    refraction_samples: int = 0
    subsurface_samples: int = 0  # samples whose subsurface light was spread (features/subsurface.py)
    probe_draws: int = 0  # draw calls of the world's probe (``world/probe.py``), counted apart
    world_guided: bool = False  # the probe found an interior: the world's directions come through its openings
    ao_texels: int = 0  # texels whose horizons were marched (half resolution: a quarter of the film)
    upload_bytes: int = 0  # bytes sent to the GPU: uniform blocks, batches built, textures of data
    mesh_upload_bytes: int = 0  # of those, vertex and index buffers (not found in a cache or the store)
    image_upload_bytes: int = 0  # image textures Blender made for this frame (``textures._first_take``)
    cpu_seconds: dict = field(default_factory=dict)  # stage -> render-thread CPU seconds (``StageClock.cpu``)
    gpu_seconds: dict = field(default_factory=dict)  # stage -> seconds waiting on the GPU (with a fence only)
    sample_cpu_seconds: list = field(default_factory=list)  # CPU seconds of each sample (its stages)
    messages: list = field(default_factory=list)  # what the user must be told about this frame
    techniques: list = field(default_factory=list)  # the frame's techniques (``features.Feature.name``)
    lit_keys: set = field(default_factory=set)  # the lit programs its draws took (``programs.LitKey``)
