"""Which samples' maps share one atlas (``shadow_pass._fits``): the batch's byte budget, the
GPU's largest texture and the tile block's length, counted as ``ShadowAtlas`` places maps."""

from devkit.session import load_penumbra

load_penumbra()

from penumbra.engine.frame import shadow_pass  # noqa: E402
from penumbra.engine.frame.shadow_maps import ShadowAtlas  # noqa: E402
from penumbra.engine.shadows.planning import MAX_SHADOW_TILES, pack_tiles  # noqa: E402


def _atlas_bytes(sizes, texel):
    slot, count, _where = pack_tiles(sizes)
    columns, rows = ShadowAtlas.grid(count)
    return columns * rows * slot * slot * texel


def test_maps_fit_while_their_atlas_is_within_the_budget():
    """The demo's maps at 160x90: two moving lights' (2048, 1024) per sample and a still one's
    512: eight samples fit 256 MiB of 32-bit depth (a 4 x 3 grid of 2048 slots, 192 MiB),
    thirteen do not (17 slots: a 5 x 4 grid, 320 MiB); the bound agrees with where ``pack_tiles`` puts them."""
    still, moving = [512], [2048, 1024]
    eight, thirteen = still + moving * 8, still + moving * 13
    assert shadow_pass._fits(eight, 4, 1 << 14)
    assert _atlas_bytes(eight, 4) == 192 << 20 <= shadow_pass.MAP_BATCH_BYTES
    assert not shadow_pass._fits(thirteen, 4, 1 << 14)
    assert _atlas_bytes(thirteen, 4) > shadow_pass.MAP_BATCH_BYTES


def test_the_largest_texture_and_the_tile_block_bound_a_batch():
    assert shadow_pass._fits([2048] * 4, 4, 4096)  # 2 x 2 slots
    assert not shadow_pass._fits([2048] * 5, 4, 4096)  # 3 x 2 slots: 6144 texels wide
    assert shadow_pass._fits([16] * MAX_SHADOW_TILES, 4, 1 << 14)
    assert not shadow_pass._fits([16] * (MAX_SHADOW_TILES + 1), 4, 1 << 14)
    # Reflective maps' 16 bytes a texel more count against the budget.
    assert shadow_pass._fits([2048] * 4, 4, 1 << 14)
    assert not shadow_pass._fits([2048] * 4, 20, 1 << 14)
