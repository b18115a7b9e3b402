"""The extension's store of what final renders keep (``engine/store.py``): least recently used
out first, never past its budget, half shed under memory pressure."""

from devkit.session import load_penumbra

load_penumbra()
from penumbra.engine.store import Kind, Store  # noqa: E402


def test_the_least_recently_used_entry_leaves_first_and_the_budget_holds():
    s = Store(budget=100)
    s.put("a", 1, "one", 40)
    s.put("a", 2, "two", 40)
    assert s.get("a", 1) == "one"  # 1 is now the more recent
    s.put("b", 3, "three", 40)  # 120 > 100: the least recently used (2) leaves
    assert s.get("a", 2) is None and s.get("a", 1) == "one" and s.get("b", 3) == "three"
    assert s.held_bytes == 80 and s.dropped == 1
    s.put("b", 4, "huge", 101)  # larger than the whole budget: not kept, nothing dropped for it
    assert s.get("b", 4) is None and s.held_bytes == 80 and s.dropped == 1
    s.put("a", 1, "again", 10)  # a key put again replaces its entry and its size
    assert s.get("a", 1) == "again" and s.held_bytes == 50


def test_memory_pressure_sheds_the_older_half():
    s = Store(budget=1000)
    for i in range(10):
        s.put("k", i, i, 10)
    s.memory = lambda: (50, 100)  # half the memory free: no pressure
    assert not s.pressure() and len(s) == 10
    s.memory = lambda: (5, 100)  # under LOW_MEMORY
    assert s.pressure()
    assert len(s) == 5 and s.held_bytes == 50
    assert s.get("k", 0) is None and s.get("k", 9) == 9  # the older half left
    s.memory = lambda: None  # a system that does not tell: nothing shed
    assert not s.pressure() and len(s) == 5


def test_a_kind_is_a_view_of_its_entries():
    s = Store(budget=1000)
    closed, levels = Kind("closed", s), Kind("levels", s)
    closed.put(b"x", True, 8)
    levels.put(b"x", (None,), 8)
    assert closed.get(b"x") is True and levels.get(b"x") == (None,)
    assert len(closed) == 1 and len(s) == 2
    closed.clear()
    assert closed.get(b"x") is None and levels.get(b"x") == (None,) and s.held_bytes == 8
    s.clear()
    assert len(s) == 0 and s.held_bytes == 0 and s.cleared == 1


def test_a_clear_outside_a_render_holds_its_values_until_the_next_render_collects_them():
    """GPU objects are freed inside a GPU context only: ``clear`` (a file load) keeps the
    values alive aside, ``collect`` (the next final render) lets them go; ``clear(now=True)``
    (unregister, exit) lets them go at once."""
    import weakref

    class Buffer:  # stands for a GPU object: what matters is when its last reference goes
        pass

    s = Store(budget=1000)
    value = Buffer()
    alive = weakref.ref(value)
    s.put("batches", b"k", value, 10)
    del value
    s.clear()
    assert len(s) == 0 and s.get("batches", b"k") is None
    assert s.released == 1 and alive() is not None  # held aside, not freed outside a context
    s.collect()
    assert s.released == 0 and alive() is None
    s.put("batches", b"k", Buffer(), 10)
    s.clear(now=True)
    assert s.released == 0
