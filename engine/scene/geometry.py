"""A mesh's triangles as the GPU draws them: the record extraction, hair and levels of detail
all build (``extract``, ``hair``, ``simplify``); and the content keys that let what is derived
from them outlive an F12 render's engine (``content_key``, the keys of ``engine/store.py``)."""

import hashlib
from dataclasses import dataclass

import numpy as np


def content_key(*arrays):
    """A digest of ``arrays``' dtypes, shapes and bytes (SHA-256: three times BLAKE2b's speed
    where the CPU has SHA extensions): what is derived from a mesh's arrays is kept by it
    between F12 renders, each a new engine that extracts anew."""
    digest = hashlib.sha256()
    for a in arrays:
        a = np.ascontiguousarray(a)
        digest.update(repr((a.dtype.str, a.shape)).encode())
        digest.update(a.data)
    return digest.digest()


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
    content: bytes | None = None  # digest of what it was extracted from (final renders' store key)

    @property
    def triangle_count(self):
        return len(self.indices)

    @property
    def nbytes(self):
        """Bytes of its arrays (what the store counts it as)."""
        arrays = (self.positions, self.normals, self.indices, self.uvs, self.colors, self.tangents, self.strands)
        return sum(a.nbytes for a in arrays if a is not None)
