"""Stages 2-6 on the GPU: the ``renderer`` sequences a frame over the draw list
(``draw_list``, ``batches``), the shadow pass (``shadow_pass``, ``shadow_maps``), the lit pass
(``lit_pass``, ``material_blocks``, ``frame_data``, ``programs``), the samples
(``sampling``) and the film (``film``), then hands the result to Blender (``output``)."""
