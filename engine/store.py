"""What final renders keep between them, by the content it is made from: one bounded store.

Every F12 render, and every frame of an animation render, is a new engine instance. Without
this store each one extracts its meshes again and uploads their vertex buffers again: for the
textured asset (a 16k-triangle mesh with UVs, tangents and a terminator offset) about 20 ms of
a 45 ms render thread. The store keeps, keyed by a digest of what each is made from
(``geometry.content_key``), never by a datablock's name:

  geometry    a mesh's extraction (``extract.geometry_from_mesh``), keyed by the arrays it is
              read from (positions, corners, faces, normals, UVs and colours it needs)
  batches     the GPU vertex and index buffers of a geometry (``frame/batches.py``), of its
              levels of detail and of its terminator streams
  closed      whether a mesh's triangles bound solids (``extract.closed_outward``)
  tangents    MikkTSpace tangents of a mesh's corners
  corners     the shadow terminator's corner data (``scene/terminator.py``)
  levels      a geometry's levels of detail (``scene/simplify.py``)
  world       the prefiltered atlas of a world's Environment Texture (``frame/world/prefilter.py``),
              keyed by the image as its SH read it back (``TextureCache._content``)

A kept texture (the world's) is freed inside a GPU context like every GPU object here
(``collect``); renderers free their own at once when let go (``Renderer.release``), not when
Python's cycle collector runs, which crashed llvmpipe when the world's atlas was first kept.

The viewport shares the pure ones (closed, tangents, corners, levels); geometry, batches and
worlds are kept for final renders only (the viewport's engine keeps its own, invalidated by the
depsgraph's updates). Textures and compiled programs have their own pools (``gpu_pool``).

One budget bounds it all (``BUDGET`` bytes, CPU and GPU copies counted alike), the least
recently used entries dropped first; an entry larger than the budget is not kept. It is emptied
when a file is loaded (``load_pre``: nothing of another file's meshes stays), when the
extension is unregistered, and at exit; under memory pressure (``pressure``: the system's
available memory below ``LOW_MEMORY`` of its total, checked when a final render begins) it
drops its older half. GPU objects are freed only inside a GPU context: what a file load
empties outside one is held aside (``clear``) until the next final render lets it go inside
its own (``collect``); room made during a render is made inside it.
"""

import atexit
import os
from collections import OrderedDict

BUDGET = 1024 * 2**20
LOW_MEMORY = 0.1  # available / total physical memory under which the store sheds (``pressure``)


def available_memory():
    """(available, total) bytes of physical memory where the system tells (Linux), else None."""
    try:
        page = os.sysconf("SC_PAGE_SIZE")
        return os.sysconf("SC_AVPHYS_PAGES") * page, os.sysconf("SC_PHYS_PAGES") * page
    except (ValueError, OSError, AttributeError):
        return None


class Store:
    """Values by (kind, key), at most ``budget`` bytes, the least recently used dropped first."""

    def __init__(self, budget=BUDGET):
        self.budget = budget
        self._items = OrderedDict()  # (kind, key) -> (value, bytes), least recently used first
        self.held_bytes = 0
        self.hits = 0
        self.misses = 0
        self.dropped = 0  # entries dropped for room or pressure since creation
        self.cleared = 0  # times emptied (file load, unregister)
        self._released = []  # what ``clear`` emptied, held until ``collect`` (inside a GPU context)
        self.memory = available_memory  # the probe ``pressure`` reads (tests may replace it)

    def __len__(self):
        return len(self._items)

    def count(self, kind):
        """How many entries of ``kind`` are held."""
        return sum(1 for k in self._items if k[0] == kind)

    def get(self, kind, key):
        item = self._items.get((kind, key))
        if item is None:
            self.misses += 1
            return None
        self._items.move_to_end((kind, key))
        self.hits += 1
        return item[0]

    def put(self, kind, key, value, nbytes):
        """Keep ``value`` (``nbytes`` large) unless it alone exceeds the budget, dropping the
        least recently used entries for room; returns ``value``."""
        nbytes = int(nbytes)
        old = self._items.pop((kind, key), None)
        if old is not None:
            self.held_bytes -= old[1]
        if nbytes > self.budget:
            return value
        self._shed(self.budget - nbytes)
        self._items[(kind, key)] = (value, nbytes)
        self.held_bytes += nbytes
        return value

    def _shed(self, limit):
        while self._items and self.held_bytes > limit:
            _key, (_value, size) = self._items.popitem(last=False)
            self.held_bytes -= size
            self.dropped += 1

    def pressure(self):
        """Shed the older half of what is held when the system's available memory is under
        ``LOW_MEMORY`` of its total; returns whether it did."""
        memory = self.memory()
        if not memory or not self._items:
            return False
        available, total = memory
        if total <= 0 or available >= LOW_MEMORY * total:
            return False
        self._shed(self.held_bytes // 2)
        return True

    def drop_kind(self, kind):
        """Forget every entry of ``kind``."""
        for key in [k for k in self._items if k[0] == kind]:
            self.held_bytes -= self._items.pop(key)[1]

    def clear(self, now=False):
        """Empty the store. Its values are held aside until ``collect`` (GPU objects must be
        freed inside a GPU context, and a file load is outside one), unless ``now`` (on
        unregister and at exit, as Blender's GPU module still runs)."""
        if not now:
            self._released.extend(value for value, _size in self._items.values())
        else:
            self._released.clear()
        self._items.clear()
        self.held_bytes = 0
        self.cleared += 1

    @property
    def released(self):
        """How many values ``clear`` holds aside for ``collect``."""
        return len(self._released)

    def collect(self):
        """Let go of what ``clear`` held aside: call it inside a GPU context."""
        self._released.clear()


STORE = Store()


class Kind:
    """One kind of ``STORE``'s entries: ``get(key)``, ``put(key, value, nbytes)``."""

    def __init__(self, kind, store=None):
        self.kind = kind
        self._store = store

    @property
    def store(self):
        return self._store if self._store is not None else STORE

    def get(self, key):
        return self.store.get(self.kind, key)

    def put(self, key, value, nbytes):
        return self.store.put(self.kind, key, value, nbytes)

    def clear(self):
        self.store.drop_kind(self.kind)

    def __len__(self):
        return self.store.count(self.kind)


def clear(now=False):
    """Empty the store (file load; ``now``: unregister, exit)."""
    STORE.clear(now)


atexit.register(clear, True)


def _on_load(*_args):
    clear()  # outside a GPU context: freed by the next final render (``Store.collect``)


def register():
    import bpy
    from bpy.app.handlers import persistent

    handler = persistent(_on_load)
    _handlers.append(handler)
    bpy.app.handlers.load_pre.append(handler)


def unregister():
    import bpy

    for handler in _handlers:
        if handler in bpy.app.handlers.load_pre:
            bpy.app.handlers.load_pre.remove(handler)
    _handlers.clear()
    clear(now=True)


_handlers = []
