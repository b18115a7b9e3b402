"""Cryptomatte (Friedman and Jones 2015, "Fully Automatic ID Mattes with Support for Motion
Blur and Transparency"): each name hashed with MurmurHash3 (32 bits, seed 0) into a float id,
every sample's ids at each pixel weighed by the film's filter, and per pixel the ids ranked by
their coverage into (id, coverage) pairs, two a pass; the names and their hashes go into the
render result's metadata (the manifest), as Cycles writes them.

Objects, materials and assets (an object's topmost parent) are the three kinds a view layer can
ask for (``KINDS``). No bpy, no gpu: the ids come from a GPU target read back each sample
(``features/passes.py``)."""

import json
import struct

import numpy as np

KINDS = ("Object", "Material", "Asset")  # CryptoObject00, ...: the id's channel in the draw's target


def murmur3_32(data, seed=0):
    """MurmurHash3's x86 32-bit hash of ``data`` (bytes)."""
    c1, c2, mask = 0xCC9E2D51, 0x1B873593, 0xFFFFFFFF
    h = seed & mask
    n = len(data) // 4
    for (k,) in struct.iter_unpack("<I", data[: 4 * n]):
        k = (k * c1) & mask
        k = ((k << 15) | (k >> 17)) & mask
        h ^= (k * c2) & mask
        h = ((h << 13) | (h >> 19)) & mask
        h = (h * 5 + 0xE6546B64) & mask
    tail = data[4 * n :]
    if tail:
        k = int.from_bytes(tail, "little")
        k = (k * c1) & mask
        k = ((k << 15) | (k >> 17)) & mask
        h ^= (k * c2) & mask
    h ^= len(data)
    h ^= h >> 16
    h = (h * 0x85EBCA6B) & mask
    h ^= h >> 13
    h = (h * 0xC2B2AE35) & mask
    h ^= h >> 16
    return h


def name_hash(name):
    """The 32-bit hash of ``name`` (its UTF-8 bytes)."""
    return murmur3_32(name.encode("utf-8"))


def hash_float(h):
    """The float an id is stored as: the hash's bits with the exponent kept within 1..254, so
    no id is a NaN, an infinity, a denormal or 0 (Blender's float encoding)."""
    exponent = min(max((h >> 23) & 0xFF, 1), 254)
    bits = (h & 0x807FFFFF) | (exponent << 23)
    return struct.unpack("<f", struct.pack("<I", bits))[0]


_IDS = {}


def name_id(name):
    """The float id of ``name``; 0 (no id) for an empty name."""
    if not name:
        return 0.0
    value = _IDS.get(name)
    if value is None:
        value = _IDS[name] = hash_float(name_hash(name))
    return value


def draw_ids(instance, material):
    """The (object, material, asset) ids a draw writes (``features/passes.py``)."""
    names = getattr(instance, "crypto_names", ("", ""))
    return (name_id(names[0]), name_id(getattr(material, "name", "")), name_id(names[1]))


def manifest(names):
    """The manifest of ``names``: a JSON object of each name's hash as 8 hex digits."""
    return json.dumps({n: f"{name_hash(n):08x}" for n in sorted(set(names)) if n}, separators=(",", ":"))


def metadata(layer, kind, names):
    """{key: value} of the render result's metadata for ``kind``'s layers of view layer
    ``layer`` (``ViewLayer.CryptoObject``): their name, hash, conversion and manifest, under
    ``cryptomatte/<7 hex digits of the name's hash>/``."""
    name = f"{layer}.Crypto{kind}"
    key = f"cryptomatte/{name_hash(name):08x}"[:19]
    return {
        f"{key}/name": name,
        f"{key}/hash": "MurmurHash3_32",
        f"{key}/conversion": "uint32_to_float32",
        f"{key}/manifest": manifest(names),
    }


class Accumulator:
    """Every sample's ids (height, width, 3: one channel per kind) weighed into each film pixel
    it reaches, kept as up to ``capacity`` (id, weight) slots a pixel and kind, and each pixel's
    total weight (its background share included). An id that finds no free slot is dropped
    (the pixel already holds ``capacity`` others)."""

    def __init__(self, size, capacity=16, kinds=(0, 1, 2)):
        width, height = size
        self.size = (width, height)
        self.kinds = tuple(kinds)  # the kinds accumulated (the others stay empty)
        self.ids = np.zeros((3, height, width, capacity), np.float32)
        self.weights = np.zeros((3, height, width, capacity), np.float64)
        self.total = np.zeros((height, width), np.float64)
        self.samples = 0
        self._inside = {}  # tap shifts -> each pixel's weight of the taps inside the image
        self.names = ((), (), ())  # each kind's names in the frame (its manifest)

    def add(self, ids, taps, gather=False):
        """One sample's ``ids`` with its ``taps`` ((x, y, weight) from a film pixel's centre:
        ``sampling.sample_taps``); ``gather``: the film takes each tap from the sample's pixel
        at (round(x), round(y)), else each pixel its own sample with the weight."""
        ids = np.asarray(ids, np.float32)
        height, width = ids.shape[:2]
        self.samples += 1
        if not gather:
            weight = float(sum(w for _x, _y, w in taps))
            every = np.ones((height, width), bool)
            for kind in self.kinds:
                self._add_dense(kind, ids[..., kind], np.full((height, width), weight), every)
            self.total += weight
            return
        shifts = tuple((int(round(x)), int(round(y)), float(w)) for x, y, w in taps)
        inside = self._inside.get(shifts)
        if inside is None:
            ones = np.ones((height, width))
            inside = self._inside[shifts] = sum(w * _shifted(ones, tx, ty, 0.0) for tx, ty, w in shifts)
        for kind in self.kinds:
            channel = ids[..., kind]
            # Where every tap sees the pixel's own id, the whole sample goes to it at once.
            same = np.ones((height, width), bool)
            for tx, ty, _w in shifts:
                same &= _shifted(channel, tx, ty, np.nan) == channel
            self._add_dense(kind, channel, inside, same)
            edge = np.flatnonzero(~same)
            for tx, ty, w in shifts:
                seen = _shifted(channel, tx, ty, np.nan).ravel()[edge]
                ok = ~np.isnan(seen)
                self._add(kind, edge[ok], seen[ok], w)
        self.total += inside

    def _add_dense(self, kind, channel, weights, mask):
        """Add ``weights`` (height, width) to the id ``channel`` holds at each pixel of
        ``mask``: in place where a pixel's first slot holds it already (most pixels, most
        samples), through ``_add_weights`` elsewhere."""
        first = self.ids[kind][..., 0]
        valid = mask & (channel != 0.0)
        hit = valid & (first == channel)
        self.weights[kind][..., 0] += np.where(hit, weights, 0.0)
        flat = np.flatnonzero(valid & ~hit)
        self._add_weights(kind, flat, channel.ravel()[flat], weights.ravel()[flat])

    def _add(self, kind, flat, values, weight):
        self._add_weights(kind, flat, values, np.full(len(flat), weight))

    def _add_weights(self, kind, flat, values, weights):
        """Add ``weights`` to id ``values`` at flat pixel indices ``flat`` (id 0: nothing)."""
        keep = values != 0.0
        flat, values, weights = flat[keep], values[keep], weights[keep]
        if not len(flat):
            return
        ids = self.ids[kind].reshape(-1, self.ids.shape[-1])
        acc = self.weights[kind].reshape(-1, self.ids.shape[-1])
        # Most pixels see the id they saw first: added in place, the rest looked up below.
        first = ids[flat, 0] == values
        acc[flat[first], 0] += weights[first]  # (each pixel once a call: no repeated index)
        flat, values, weights = flat[~first], values[~first], weights[~first]
        if not len(flat):
            return
        slots = ids[flat]
        match = slots == values[:, None]
        found = match.any(axis=1)
        empty = slots == 0.0
        slot = np.where(found, match.argmax(axis=1), empty.argmax(axis=1))
        ok = found | empty.any(axis=1)
        rows, cols = flat[ok], slot[ok]
        ids[rows, cols] = values[ok]
        np.add.at(acc, (rows, cols), weights[ok])

    def layers(self, kind, levels):
        """The (levels + 1) // 2 passes of ``kind`` (index into ``KINDS``): (height, width, 4)
        each, (id, coverage) of ranks 2i and 2i + 1, coverage the id's share of the pixel's
        total weight."""
        slots = self.ids.shape[-1]
        ids = self.ids[kind].reshape(-1, slots).copy()
        cov = self.weights[kind].reshape(-1, slots).copy()
        # Only pixels that met several ids need ranking (a pixel's first id sits in slot 0).
        several = np.flatnonzero(ids[:, 1] != 0.0)
        if len(several):
            order = np.argsort(-cov[several], axis=-1, kind="stable")
            ids[several] = np.take_along_axis(ids[several], order, -1)
            cov[several] = np.take_along_axis(cov[several], order, -1)
        total = np.where(self.total > 0.0, self.total, 1.0).reshape(-1, 1)
        shape = self.total.shape + (slots,)
        ids = ids.reshape(shape)
        cov = (cov / total).astype(np.float32).reshape(shape)
        count = (min(int(levels), 16) + 1) // 2
        out = []
        for i in range(count):
            layer = np.zeros(self.total.shape + (4,), np.float32)
            for j in range(2):
                rank = 2 * i + j
                if rank < ids.shape[-1]:
                    layer[..., 2 * j] = ids[..., rank]
                    layer[..., 2 * j + 1] = cov[..., rank]
            out.append(layer)
        return out

    def coverage(self, kind, name):
        """The coverage of ``name``'s id at each pixel (height, width): what a matte reads."""
        value = np.float32(name_id(name))
        weights = np.where(self.ids[kind] == value, self.weights[kind], 0.0).sum(-1)
        return weights / np.where(self.total > 0.0, self.total, 1.0)


def _shifted(image, tx, ty, fill):
    """``image`` at pixel (x + tx, y + ty) for each pixel (x, y); ``fill`` beyond its edge."""
    out = np.full(image.shape, fill, dtype=np.result_type(image, np.asarray(fill)))
    height, width = image.shape[:2]
    ys, yd = (slice(ty, height), slice(0, height - ty)) if ty >= 0 else (slice(0, height + ty), slice(-ty, height))
    xs, xd = (slice(tx, width), slice(0, width - tx)) if tx >= 0 else (slice(0, width + tx), slice(-tx, width))
    out[yd, xd] = image[ys, xs]
    return out
