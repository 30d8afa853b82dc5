"""``like(x, ref)``: x converted to the float type of ``ref``, inside compiled code.

Kernels are compiled once for float64 and once for float32 states.  numba
promotes float32 mixed with an integer or a float64 literal to float64, so
a kernel converts integers (column differences, zero) with ``like`` and
stays in the state's type.
"""
import numpy as np
from numba import types
from numba.extending import overload


def like(x, ref):
    """Python fallback: the value of ``x`` in the NumPy type of ``ref``."""
    return np.asarray(ref).dtype.type(x)


@overload(like, inline="always")
def _like(x, ref):
    if ref == types.float32:
        return lambda x, ref: np.float32(x)
    return lambda x, ref: np.float64(x)
