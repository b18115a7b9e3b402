"""The world's light, in three parts with distinct names:

* ``sh_light``: its unshadowed light on every surface, order-2 spherical harmonics of its
  colour or Environment Texture (projected on the GPU: ``with_sh_light``), which the lit
  shader reads as the world's SH light (``shaders/lib/lit_world.glsl``);
* ``directions``: its light with visibility, a few directions per sample drawn from its
  radiance, each a sun with a shadow map (``world_lights``), which shadow the SH light as a
  ratio (``WORLD_RATIO``) or, through light portals, carry all of it;
* ``occlusion``: the screen-space ambient occlusion of its SH light over a camera depth
  prepass (``WorldAO``, ``shaders/lib/gtao.glsl``).
"""
