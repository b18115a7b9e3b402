"""A mesh's triangles as the GPU draws them: the record extraction, hair and levels of detail
all build (``extract``, ``hair``, ``simplify``)."""

from dataclasses import dataclass

import numpy as np


@dataclass
class Geometry:
    """Triangles of one mesh as an indexed vertex buffer, the triangles sorted by material slot.

    A vertex is a mesh vertex when the mesh is smooth throughout (normals on points), else a
    face corner (flat or mixed shading: normals on faces or corners), as Blender's own draw
    code does; triangles index those vertices."""

    positions: np.ndarray  # (vertices, 3) float32
    normals: np.ndarray  # (vertices, 3) float32
    indices: np.ndarray  # (triangles, 3) int32 into positions
    ranges: list  # (material index, first triangle, triangle count)
    bounds: np.ndarray  # (2, 3) local min/max of the drawn vertices; NaN when empty
    uvs: np.ndarray | None = None  # (vertices, 2) float32: the UV map a material's textures read
    colors: np.ndarray | None = None  # (vertices, 4) float32 linear: a colour attribute
    tangents: np.ndarray | None = None  # (vertices, 4) float32 MikkTSpace tangent and sign; w 0: none
    # Hair strips (``hair.strips``): (vertices, 2) float32 side (-1, 1) and radius; positions
    # then lie on the strands' centre lines and normals are their tangents.
    strands: np.ndarray | None = None
    closed: bool = False  # the triangles bound solids with outward normals (``closed_outward``)
    smooth: bool = False  # some faces are smooth-shaded (normals not all the faces' own)
    messages: tuple = ()
    deps: frozenset = frozenset()
    serial: int = 0  # distinguishes rebuilt geometry of the same key (GPU batches key on it)

    @property
    def triangle_count(self):
        return len(self.indices)
