"""Evaluate GLSL functions of ``shaders/nodes/`` on the GPU at given points, for the tests that
compare them with their numpy twins (``devkit.texture_reference``).

``evaluate(gpu_call, libs, body, *inputs)``: each input is an (n, 4) float32 array uploaded as an
RGBA32F texture ``in0``, ``in1``, ...; the fragment at texel i reads ``vec4 a0 = texelFetch(in0,
...)``, ``a1``, ... and runs ``body``, which must assign ``vec4 result``. Returns the n results as
an (n, 4) float32 array. Several bodies run in one GPU call with ``evaluate_many``."""

import numpy as np

from .session import ROOT

WIDTH = 64


def node_sources(libs):
    return "".join((ROOT / "shaders" / "nodes" / name).read_text(encoding="utf-8") + "\n" for name in libs)


def _shader(libs, body, n_inputs):
    import gpu

    info = gpu.types.GPUShaderCreateInfo()
    info.vertex_in(0, "VEC2", "pos")
    for i in range(n_inputs):
        info.sampler(i, "FLOAT_2D", f"in{i}")
    info.fragment_out(0, "VEC4", "out_color")
    info.vertex_source("void main() { gl_Position = vec4(pos, 0.0, 1.0); }")
    reads = "".join(f"  vec4 a{i} = texelFetch(in{i}, ivec2(gl_FragCoord.xy), 0);\n" for i in range(n_inputs))
    info.fragment_source(
        node_sources(libs) + "void main()\n{\n" + reads + "  vec4 result = vec4(0.0);\n" + body + "\n"
        "  out_color = result;\n}\n"
    )
    return gpu.shader.create_from_info(info)


def evaluate_many(gpu_call, jobs):
    """``jobs``: [(libs, body, [inputs])]; returns [(n, 4) arrays] from one GPU call."""

    def run(engine, depsgraph):
        import gpu
        from gpu_extras.batch import batch_for_shader

        from penumbra.engine.frame.film import texture_array

        results = []
        for libs, body, inputs in jobs:
            n = len(inputs[0])
            h = (n + WIDTH - 1) // WIDTH
            textures = []
            for a in inputs:
                data = np.zeros((h * WIDTH, 4), np.float32)
                data[:n] = a
                buf = gpu.types.Buffer("FLOAT", data.size, data.ravel().tolist())
                textures.append(gpu.types.GPUTexture((WIDTH, h), format="RGBA32F", data=buf))
            shader = _shader(libs, body, len(inputs))
            out = gpu.types.GPUTexture((WIDTH, h), format="RGBA32F")
            fb = gpu.types.GPUFrameBuffer(color_slots=(out,))
            batch = batch_for_shader(shader, "TRIS", {"pos": ((-1, -1), (3, -1), (-1, 3))})
            with fb.bind():
                gpu.state.viewport_set(0, 0, WIDTH, h)
                gpu.state.depth_test_set("NONE")
                gpu.state.blend_set("NONE")
                shader.bind()
                for i, tex in enumerate(textures):
                    shader.uniform_sampler(f"in{i}", tex)
                batch.draw(shader)
            results.append(texture_array(out, 4).reshape(-1, 4)[:n].copy())
        return results

    return gpu_call(run)


def evaluate(gpu_call, libs, body, *inputs):
    return evaluate_many(gpu_call, [(libs, body, list(inputs))])[0]
