"""GPU batches of the scene's geometry: built once per mesh datablock (and per level of
detail), kept while the geometry is in the scene, rebuilt only when it changes."""


class Batches:
    """(all-triangles batch, [(material index, batch)]) per Geometry: ``whole`` for shadow
    maps, the parts for the lit pass."""

    def __init__(self):
        self.meshes = {}  # (geometry key, serial) -> (whole, parts)
        self.levels = {}  # (geometry key, serial, level) -> (whole, parts) of ``simplify.simplified``
        self._used = set()  # the levels drawn this frame (lit pass or shadow maps)

    def get(self, key, geo):
        """The batches of the snapshot's geometry ``key``, built on first use of its serial."""
        return self._get(self.meshes, (key, geo.serial), geo)

    def level(self, key, lod):
        """The batches of a level of detail ``lod`` (``simplify.simplified``), kept under
        ``key`` = (geometry key, serial, level)."""
        self._used.add(key)
        return self._get(self.levels, key, lod)

    def keep(self, live):
        """At the end of a frame: release the batches of geometry no longer in the snapshot
        (``live``: (key, serial) pairs) and of levels of detail this frame did not draw."""
        for stale in [k for k in self.meshes if k not in live]:
            del self.meshes[stale]
        for stale in [k for k in self.levels if k not in self._used]:
            del self.levels[stale]
        self._used = set()

    @staticmethod
    def _get(cache, cache_key, geo):
        import gpu

        cached = cache.get(cache_key)
        if cached is not None:
            return cached
        fmt = gpu.types.GPUVertFormat()
        attrs = {"pos": geo.positions, "nor": geo.normals, "uv": geo.uvs, "col": geo.colors, "tan": geo.tangents}
        attrs = {name: data for name, data in attrs.items() if data is not None}
        for name, data in attrs.items():
            fmt.attr_add(id=name, comp_type="F32", len=data.shape[1], fetch_mode="FLOAT")
        vbo = gpu.types.GPUVertBuf(fmt, len(geo.positions))
        for name, data in attrs.items():
            vbo.attr_fill(name, data)
        whole = gpu.types.GPUBatch(type="TRIS", buf=vbo, elem=gpu.types.GPUIndexBuf(type="TRIS", seq=geo.indices))
        parts = []
        for mat_index, first, count in geo.ranges:
            if first == 0 and count == len(geo.indices):
                parts.append((mat_index, whole))
                continue
            ibo = gpu.types.GPUIndexBuf(type="TRIS", seq=geo.indices[first : first + count])
            parts.append((mat_index, gpu.types.GPUBatch(type="TRIS", buf=vbo, elem=ibo)))
        cache[cache_key] = (whole, parts)
        return cache[cache_key]
