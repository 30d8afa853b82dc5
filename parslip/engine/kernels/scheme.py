"""The load ramp of the time scheme, written once for the compiled loop, the reference engine and the state.

ramp_share(n, n_ramp)     the share of F_N acting at step n: min(1, n / n_ramp), 1 without a ramp

The damped update's factors are the damping's (``model.damping.Damping``).
"""
from numba import njit


@njit(cache=True, inline="always", _nrt=False)
def ramp_share(n, n_ramp):
    """min(1, n / n_ramp): the share of the normal load F_N acting at step n (1 when n_ramp is 0)."""
    return 1.0 if n_ramp == 0 else min(1.0, n / n_ramp)
