"""Stage 1, extract: Blender's depsgraph -> a plain snapshot of the frame (mesh instances and
their geometry, materials, lights, world, camera), with image textures and levels of detail.
Nothing here draws; the later stages read only the snapshot."""
