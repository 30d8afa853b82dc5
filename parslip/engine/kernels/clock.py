"""``now_ns()``: a monotonic clock in compiled code, for the loop's phase timers.

Calls the C library's ``clock_gettime(CLOCK_MONOTONIC)`` by symbol name (a
vDSO call, about 20 ns), so the compiled loop can say where its time goes:
interface bonds, stencil, halo exchange, checks.  Resolved by name at link
time, so the compiled code stays cacheable.
"""
import ctypes
import ctypes.util

import numpy as np
from numba import njit, types

import llvmlite.binding as _llb

_libc = ctypes.util.find_library("c")
if _libc:
    _llb.load_library_permanently(_libc)

CLOCK_MONOTONIC = 1
_clock_gettime = types.ExternalFunction("clock_gettime", types.int32(types.int32, types.voidptr))


# Inlined by numba: the step and the frames read the clock, and a job compiles those on two ranks at once
# (engine.compile); compiled on its own, both would compile it.
@njit(cache=True, inline="always")
def now_ns(buf):
    """Nanoseconds of the monotonic clock; ``buf`` is a scratch int64 array of length 2 (struct timespec)."""
    _clock_gettime(np.int32(CLOCK_MONOTONIC), buf.ctypes.data)
    return buf[0] * 1_000_000_000 + buf[1]
