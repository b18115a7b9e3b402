"""Each material's uniform block (``programs.MATERIAL_STRUCT``), built once per Material read:
the lit pass and the shadow pass's alpha cutouts bind the same block."""

import numpy as np

from ..scene.materials import CHANNELS, EXTENSION, INTERPOLATION
from .programs import MATERIAL_STRUCT, NODE_CONSTANT_STRUCT

MAX_BLOCKS = 4096  # blocks kept before the cache starts afresh (materials of past snapshots)


class MaterialBlocks:
    def __init__(self):
        self._blocks = {}  # id(Material) -> (Material, GPUUniformBuf)
        self._constants = {}  # id(Material) -> (Material, GPUUniformBuf) of its node tree
        self.uploaded = 0  # bytes of blocks sent to the GPU since creation

    def __len__(self):
        return len(self._blocks)

    def get(self, mat):
        """The MaterialData block of ``mat``."""
        import gpu

        cached = self._blocks.get(id(mat))
        if cached is not None and cached[0] is mat:
            return cached[1]
        row = {
            "base_color": tuple(mat.base_color)[:4],
            "emission": tuple(mat.emission)[:3],
            "roughness": float(mat.roughness),
            "metallic": float(mat.metallic),
            "specular": tuple(mat.f0),
            "alpha": float(mat.alpha),
            "normal_strength": float(mat.normal_strength),
            "transmission": float(mat.transmission) if mat.transmits else 0.0,
            "ior": float(mat.ior),
        }
        for channel in CHANNELS:
            ref = mat.textures.get(channel)
            rows = ref.transform if ref is not None else ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0))
            row[f"{channel}_uv_u"] = (*rows[0], 0.0)
            row[f"{channel}_uv_v"] = (*rows[1], 0.0)
            mode = (0, 0, 0, 0)
            if ref is not None:
                mode = (
                    INTERPOLATION.get(ref.interpolation, 1),
                    EXTENSION.get(ref.extension, 0),
                    int(ref.output == "Alpha"),
                    int(ref.component),
                )
            row[f"{channel}_mode"] = mode
        raw = MATERIAL_STRUCT.pack([row]).tobytes()
        self.uploaded += len(raw)
        ubo = gpu.types.GPUUniformBuf(raw)
        if len(self._blocks) > MAX_BLOCKS:
            self._blocks.clear()
        self._blocks[id(mat)] = (mat, ubo)
        return ubo

    def constants(self, mat):
        """The node_constants block of ``mat``'s compiled node tree (``Material.tree``)."""
        import gpu

        cached = self._constants.get(id(mat))
        if cached is not None and cached[0] is mat:
            return cached[1]
        rows = mat.tree.constants if len(mat.tree.constants) else np.zeros((1, 4), np.float32)
        data = NODE_CONSTANT_STRUCT.pack([{"v": row} for row in rows])
        self.uploaded += data.nbytes
        ubo = gpu.types.GPUUniformBuf(data.tobytes())
        if len(self._constants) > MAX_BLOCKS:
            self._constants.clear()
        self._constants[id(mat)] = (mat, ubo)
        return ubo
