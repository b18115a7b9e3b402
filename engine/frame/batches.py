"""GPU batches of the scene's geometry: built once per mesh datablock (and per level of
detail), kept while the geometry is in the scene, rebuilt only when it changes. Final renders
also keep them between renders in the extension's store (``engine/store.py``), by the content
of the geometry they hold (``Geometry.content``): a second F12 of an unchanged scene uploads
no vertex data."""

import numpy as np

from ..scene import terminator


class Batches:
    """(all-triangles batch, [(material index, batch)]) per Geometry: ``whole`` for shadow
    maps, the parts for the lit pass."""

    def __init__(self, store=None):
        self.store = store  # ``store.Store`` of final renders, or None
        self.meshes = {}  # (geometry key, serial) -> (whole, parts)
        self.levels = {}  # (geometry key, serial, level) -> (whole, parts) of ``simplify.simplified``
        self.terminators = {}  # (geometry key, serial[, level]) -> parts with the terminator's corner data
        self._used = set()  # the levels drawn this frame (lit pass or shadow maps)
        self.uploaded = 0  # bytes of vertex and index buffers sent to the GPU since creation

    def get(self, key, geo):
        """The batches of the snapshot's geometry ``key``, built on first use of its serial."""
        return self._get(self.meshes, (key, geo.serial), geo)

    def level(self, key, lod):
        """The batches of a level of detail ``lod`` (``simplify.simplified``), kept under
        ``key`` = (geometry key, serial, level)."""
        self._used.add(key)
        return self._get(self.levels, key, lod)

    def terminator(self, cache_key, geo):
        """The lit pass's parts of ``geo`` for objects with a Shadow Terminator geometry
        offset: one vertex per triangle corner (no index sharing), each with its triangle's
        ``terminator.corner_data`` beside the usual attributes; built on first use of
        ``cache_key`` ((geometry key, serial) or a level's key)."""
        self._used.add(cache_key)
        cached = self.terminators.get(cache_key)
        if cached is None:
            buffers = self._kept("terminator", geo)
            if buffers is None:
                buffers = _terminator_buffers(geo)
                nbytes = _upload_bytes(_attributes(geo), 3 * len(geo.indices), len(geo.indices))
                self.uploaded += nbytes
                self._keep("terminator", geo, buffers, nbytes)
            vbo, ibos = buffers
            cached = [(mat_index, _batch(vbo, ibo)) for mat_index, ibo in ibos]
        self.terminators[cache_key] = cached
        return cached

    def _kept(self, kind, geo):
        """What the store holds of ``kind`` for ``geo``'s content, or None."""
        if self.store is None or geo.content is None:
            return None
        return self.store.get(kind, geo.content)

    def _keep(self, kind, geo, value, nbytes):
        if self.store is not None and geo.content is not None:
            self.store.put(kind, geo.content, value, nbytes)

    def keep(self, live):
        """At the end of a frame: release the batches of geometry no longer in the snapshot
        (``live``: (key, serial) pairs) and of levels of detail and terminator streams this
        frame did not draw."""
        for stale in [k for k in self.meshes if k not in live]:
            del self.meshes[stale]
        for stale in [k for k in self.levels if k not in self._used]:
            del self.levels[stale]
        for stale in [k for k in self.terminators if k not in live and k not in self._used]:
            del self.terminators[stale]
        self._used = set()

    def _get(self, cache, cache_key, geo):
        """The (whole, parts) batches of ``geo``. The store keeps their vertex and index
        buffers (the uploaded data) between final renders, not the batches: each render makes
        its own batch objects over them (no upload), so no vertex-array state a batch keeps
        per GPU context outlives a render."""
        cached = cache.get(cache_key)
        if cached is not None:
            return cached
        buffers = self._kept("batches", geo)
        if buffers is None:
            nbytes = _upload_bytes(_attributes(geo), len(geo.positions), len(geo.indices))
            self.uploaded += nbytes
            buffers = _mesh_buffers(geo)
            self._keep("batches", geo, buffers, nbytes)
        vbo, whole_ibo, ibos = buffers
        whole = _batch(vbo, whole_ibo)
        parts = [(mat_index, whole if ibo is None else _batch(vbo, ibo)) for mat_index, ibo in ibos]
        cache[cache_key] = (whole, parts)
        return cache[cache_key]


def _batch(vbo, ibo):
    import gpu

    return gpu.types.GPUBatch(type="TRIS", buf=vbo, elem=ibo)


def _mesh_buffers(geo):
    """(vertex buffer, index buffer of every triangle, [(material index, its index buffer, or
    None where it is every triangle)]) of ``geo``."""
    import gpu

    vbo = _vertex_buffer(_attributes(geo), len(geo.positions))
    whole = gpu.types.GPUIndexBuf(type="TRIS", seq=geo.indices)
    ibos = []
    for mat_index, first, count in geo.ranges:
        if first == 0 and count == len(geo.indices):
            ibos.append((mat_index, None))
        else:
            ibos.append((mat_index, gpu.types.GPUIndexBuf(type="TRIS", seq=geo.indices[first : first + count])))
    return vbo, whole, ibos


def _upload_bytes(attrs, vertices, triangles):
    """Bytes a batch of ``vertices`` with ``attrs`` (32-bit floats) and ``triangles`` sends."""
    return vertices * 4 * sum(int(a.shape[1]) for a in attrs.values()) + triangles * 12


def _attributes(geo):
    """The vertex attributes of ``geo`` by shader input name (those it has)."""
    attrs = {
        "pos": geo.positions,
        "nor": geo.normals,
        "uv": geo.uvs,
        "col": geo.colors,
        "tan": geo.tangents,
        "hair": geo.strands,
    }
    return {name: data for name, data in attrs.items() if data is not None}


def _vertex_buffer(attrs, count):
    import gpu

    fmt = gpu.types.GPUVertFormat()
    for name, data in attrs.items():
        fmt.attr_add(id=name, comp_type="F32", len=data.shape[1], fetch_mode="FLOAT")
    vbo = gpu.types.GPUVertBuf(fmt, count)
    for name, data in attrs.items():
        vbo.attr_fill(name, data)
    return vbo


def _terminator_buffers(geo):
    """(vertex buffer, [(material index, index buffer)]) of ``geo`` with a vertex per triangle
    corner carrying the geometry offset's corner data (``terminator.ATTRIBUTES``)."""
    import gpu

    corners = np.ascontiguousarray(geo.indices, np.int32).ravel()
    attrs = {name: np.ascontiguousarray(data[corners]) for name, data in _attributes(geo).items()}
    attrs.update(terminator.corner_data_cached(geo.positions, geo.normals, geo.indices))
    vbo = _vertex_buffer(attrs, len(corners))
    ibos = []
    for mat_index, first, count in geo.ranges:
        seq = np.arange(3 * first, 3 * (first + count), dtype=np.int32).reshape(-1, 3)
        ibos.append((mat_index, gpu.types.GPUIndexBuf(type="TRIS", seq=seq)))
    return vbo, ibos
