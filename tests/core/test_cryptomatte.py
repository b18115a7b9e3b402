"""Cryptomatte's hashes, float ids and per-pixel ranking (engine/frame/cryptomatte.py), against
MurmurHash3's published test vectors and numpy references of the coverage."""

import json
import struct

import numpy as np
import pytest

from devkit.session import load_penumbra

load_penumbra()
from penumbra.engine.frame import cryptomatte, sampling  # noqa: E402


@pytest.mark.parametrize(
    "data, seed, expected",
    [
        (b"", 0, 0x00000000),
        (b"", 1, 0x514E28B7),
        (b"\x00\x00\x00\x00", 0, 0x2362F9DE),
        (b"hello", 0, 0x248BFA47),
        (b"Hello, world!", 1234, 0xFAF6CDB3),
        (b"The quick brown fox jumps over the lazy dog", 0, 0x2E4FF723),
    ],
)
def test_murmur3_matches_its_published_vectors(data, seed, expected):
    assert cryptomatte.murmur3_32(data, seed) == expected


def test_float_ids_are_finite_normal_and_keep_the_hash_bits_but_the_exponent():
    rng = np.random.default_rng(3)
    for h in [0, 0xFFFFFFFF, 0x7F800000, 0x00000001, *rng.integers(0, 2**32, 2000).tolist()]:
        f = cryptomatte.hash_float(int(h))
        assert np.isfinite(f) and f != 0.0 and abs(f) >= np.finfo(np.float32).tiny
        bits = struct.unpack("<I", struct.pack("<f", f))[0]
        assert bits & 0x807FFFFF == int(h) & 0x807FFFFF  # sign and mantissa kept
    assert cryptomatte.name_id("") == 0.0


def test_the_manifest_and_metadata_name_each_layer_as_cycles_does():
    meta = cryptomatte.metadata("ViewLayer", "Object", ["Cube", "Ball", "Cube", ""])
    prefix = f"cryptomatte/{cryptomatte.name_hash('ViewLayer.CryptoObject'):08x}"[:19]
    assert meta[f"{prefix}/name"] == "ViewLayer.CryptoObject"
    assert meta[f"{prefix}/hash"] == "MurmurHash3_32" and meta[f"{prefix}/conversion"] == "uint32_to_float32"
    manifest = json.loads(meta[f"{prefix}/manifest"])
    assert manifest == {"Ball": f"{cryptomatte.name_hash('Ball'):08x}", "Cube": f"{cryptomatte.name_hash('Cube'):08x}"}


def _edge_ids(width, height, split):
    """Id A left of column ``split``, B from it on, the background (0) in the top row."""
    a, b = cryptomatte.name_id("A"), cryptomatte.name_id("B")
    ids = np.zeros((height, width, 3), np.float32)
    ids[:, :split, 0] = a
    ids[:, split:, 0] = b
    ids[-1] = 0.0
    return ids


def test_one_sample_a_pixel_ranks_the_id_it_saw_with_full_coverage():
    acc = cryptomatte.Accumulator((8, 4))
    acc.add(_edge_ids(8, 4, 3), [(0.0, 0.0, 1.0)])
    (layer,) = acc.layers(0, 2)
    assert np.all(layer[:3, :3, 0] == cryptomatte.name_id("A")) and np.all(layer[:3, 3:, 0] == cryptomatte.name_id("B"))
    assert np.all(layer[:3, :, 1] == 1.0) and np.all(layer[:3, :, 2:] == 0.0)
    assert np.all(layer[3] == 0.0)  # the background ranks nothing


def test_gathered_samples_give_the_filters_coverage_across_an_edge():
    """Samples gathered through the film's window: each pixel's coverage of A is the share of
    its taps' weights that fall on A's pixels (numpy reference), the ranks in order, and A's and
    B's coverages add up to the whole pixel."""
    filter_size = 1.5
    width, height, split = 12, 6, 5
    acc = cryptomatte.Accumulator((width, height))
    ids = _edge_ids(width, height, split)
    ids[-1] = ids[0]  # no background here
    expected_a = np.zeros((height, width))
    total = np.zeros((height, width))
    for s in range(8):
        taps = sampling.sample_taps(s, filter_size)
        acc.add(ids, taps, gather=True)
        for x, y, w in taps:
            tx, ty = int(round(x)), int(round(y))
            for py in range(height):
                for px in range(width):
                    qx, qy = px + tx, py + ty
                    if 0 <= qx < width and 0 <= qy < height:
                        total[py, px] += w
                        expected_a[py, px] += w * (qx < split)
    cov_a = acc.coverage(0, "A")
    cov_b = acc.coverage(0, "B")
    np.testing.assert_allclose(cov_a, expected_a / total, atol=1e-6)
    np.testing.assert_allclose(cov_a + cov_b, 1.0, atol=1e-6)
    assert 0.0 < cov_a[2, split] < 0.5 < cov_a[2, split - 1] < 1.0  # the edge is soft, each side its own
    (first,) = acc.layers(0, 2)
    assert np.all(first[..., 1] >= first[..., 3])  # ranked by coverage


def test_a_pixel_keeps_its_strongest_ids_when_more_meet_than_it_holds():
    acc = cryptomatte.Accumulator((1, 1), capacity=2)
    for name, weight in (("A", 0.5), ("B", 0.3), ("C", 0.2)):
        ids = np.zeros((1, 1, 3), np.float32)
        ids[0, 0, 0] = cryptomatte.name_id(name)
        acc.add(ids, [(0.0, 0.0, weight)])
    (layer,) = acc.layers(0, 2)
    assert layer[0, 0, 0] == cryptomatte.name_id("A") and layer[0, 0, 1] == pytest.approx(0.5)
    assert layer[0, 0, 2] == cryptomatte.name_id("B") and layer[0, 0, 3] == pytest.approx(0.3)
