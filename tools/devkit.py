"""Dev-side helpers shared by the tests and the tools (not shipped in the extension zip):
load the repository as the ``penumbra`` package, and run code inside a GPU context."""

import importlib.util
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def load_penumbra():
    """Import the repository root as the package ``penumbra`` (its folder name may differ)."""
    if "penumbra" in sys.modules:
        return sys.modules["penumbra"]
    spec = importlib.util.spec_from_file_location(
        "penumbra", ROOT / "__init__.py", submodule_search_locations=[str(ROOT)]
    )
    module = importlib.util.module_from_spec(spec)
    sys.modules["penumbra"] = module
    spec.loader.exec_module(module)
    return module


def eevee_id():
    """EEVEE's engine id on this Blender: 'BLENDER_EEVEE_NEXT' (4.2-4.5) or 'BLENDER_EEVEE' (5.x)."""
    import bpy

    items = {item.identifier for item in bpy.types.RenderSettings.bl_rna.properties["engine"].enum_items}
    for candidate in ("BLENDER_EEVEE_NEXT", "BLENDER_EEVEE"):
        if candidate in items:
            return candidate
    raise RuntimeError(f"no EEVEE engine among {sorted(items)}")


class GpuRunner:
    """Runs ``fn(engine, depsgraph)`` inside a RenderEngine.render() call, where Blender's gpu
    module can draw in background mode. The engine class is built on Penumbra's engine core,
    so ``engine.render_frame`` and ``engine.draw_display`` are the production code paths.

    Use as ``runner = GpuRunner(); runner.register(); runner(fn); runner.unregister()``. The
    current scene needs a camera (Blender refuses to render without one)."""

    def __init__(self):
        import bpy
        from penumbra.engine.render_engine import PenumbraEngineCore

        runner = self

        class PENUMBRA_GPU_RUNNER(PenumbraEngineCore, bpy.types.RenderEngine):
            bl_idname = "PENUMBRA_GPU_RUNNER"
            bl_label = "Penumbra GPU runner"
            bl_use_gpu_context = True

            def render(self, depsgraph):
                try:
                    runner._result = runner._job(self, depsgraph)
                except Exception as exc:  # handed back to the caller
                    runner._error = exc
                finally:
                    self.free_gpu()  # while the GPU context is active

            def update_render_passes(self, scene=None, renderlayer=None):
                self.register_pass(scene, renderlayer, "Combined", 4, "RGBA", "COLOR")

        self.engine_class = PENUMBRA_GPU_RUNNER
        self._job = self._result = self._error = None

    def register(self):
        import bpy

        bpy.utils.register_class(self.engine_class)

    def unregister(self):
        import bpy

        bpy.utils.unregister_class(self.engine_class)

    def __call__(self, fn):
        import bpy

        scene = bpy.context.scene
        old = scene.render.engine
        scene.render.engine = self.engine_class.bl_idname
        self._job, self._result, self._error = fn, None, None
        try:
            bpy.ops.render.render(write_still=False)
        finally:
            scene.render.engine = old
        if self._error is not None:
            raise self._error
        return self._result
