"""Stage 2's mathematics, without a GPU: light-space projections and fits (``lightspace``),
which maps a frame needs (``planning``), the lights each screen bin sees (``light_bins``) and
the filter kernels (``kernels``). The depth pass that draws the planned maps is
``frame.shadow_pass``."""
