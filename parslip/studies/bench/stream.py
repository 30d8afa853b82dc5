"""Memory bandwidth of this machine: a STREAM-like triad a = b + s c, compiled.

Arrays of 2^24 doubles (128 MiB each) are far larger than the caches, so
the triad measures main memory: 24 bytes move per element (two reads, one
write; the write-allocate read is not counted, as in STREAM).
"""
from __future__ import annotations

import time

import numpy as np
from numba import njit

N = 1 << 24


@njit(cache=True)
def _triad(a, b, c, s):
    for i in range(a.shape[0]):
        a[i] = b[i] + s * c[i]


def triad_gbs(n: int = N, repeats: int = 5) -> float:
    """Best of ``repeats`` triads, in GB/s (10^9 bytes per second)."""
    a, b, c = np.zeros(n), np.ones(n), np.full(n, 2.0)
    _triad(a, b, c, 3.0)
    best = np.inf
    for _ in range(repeats):
        t = time.perf_counter()
        _triad(a, b, c, 3.0)
        best = min(best, time.perf_counter() - t)
    return 24.0 * n / best / 1e9


if __name__ == "__main__":          # one process of a concurrent measurement (the suite runs 2 at once)
    import json
    print(json.dumps({"triad_gbs": triad_gbs()}))
