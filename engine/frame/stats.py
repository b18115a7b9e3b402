"""What a frame did (``FrameStats``): read by tests, the benchmarks and the render report."""

from dataclasses import dataclass, field


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
    cancelled: bool = False  # on_sample asked to stop before the last sample
    stopped: str = ""  # why the frame ended before its last sample: "converged" or "time limit"
    pixels_converged: int = 0  # pixels adaptive sampling stopped (Noise Threshold)
    pixels_settled: int = 0  # of those, pixels settled after the first sample(s) (``settle.py``)
    pixel_samples_skipped: int = 0  # of the samples taken, those converged pixels were not shaded in (summed)
    lights_out_of_view: int = 0  # lights that reach no visible surface: no map, no shading
    closed_culled: int = 0  # closed instances drawn without back faces (lit pass and each map)
    simplified: int = 0  # instances drawn at a level of detail (``simplify``; ``triangles`` counts its)
    debug_legend: str = ""  # a debug view's legend: what its colours mean (``debug_view``)
    binned: bool = False  # the lit pass looped over each screen bin's lights only
    messages: list = field(default_factory=list)  # what the user must be told about this frame
