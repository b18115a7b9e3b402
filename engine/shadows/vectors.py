"""Small vector helpers the planning code calls many times a sample (numpy only)."""

import numpy as np


def cross(a, b):
    """``np.cross`` of 3-vectors along the last axis (broadcast): the same products and
    differences, so the same bits, without its axis bookkeeping, several times faster on the
    small arrays planning makes every sample."""
    a = np.asarray(a)
    b = np.asarray(b)
    if a.ndim == 1 and b.ndim == 1 and a.dtype == b.dtype == np.float64:
        a0, a1, a2 = a.tolist()
        b0, b1, b2 = b.tolist()
        return np.array((a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0))
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack(np.broadcast_arrays(a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0), axis=-1)
