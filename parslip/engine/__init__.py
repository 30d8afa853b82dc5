"""The time loop: one rank's state, the compiled kernels and the load phases (ramp, settle, drive)."""
# Before any kernel is defined: numba's cache in a folder keyed by the kernels' sources (io.cache).
from ..io.cache import use_kernel_cache

use_kernel_cache()
