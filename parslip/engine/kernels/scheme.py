"""The time scheme's two rules, written once for the compiled loop, the reference engine and the state.

ramp_share(n, n_ramp)     the share of F_N acting at step n: min(1, n / n_ramp), 1 without a ramp
verlet_constant(dt, zeta) C = dt^2 / (1 + zeta dt / 2) of the damped Verlet update (m = 1):
                          u(t+dt) (1 + zeta dt/2) = 2 u(t) - (1 - zeta dt/2) u(t-dt) + dt^2 F(t)
"""
from numba import njit


@njit(cache=True, inline="always", _nrt=False)
def ramp_share(n, n_ramp):
    """min(1, n / n_ramp): the share of the normal load F_N acting at step n (1 when n_ramp is 0)."""
    return 1.0 if n_ramp == 0 else min(1.0, n / n_ramp)


def verlet_constant(dt: float, zeta: float) -> float:
    """C = dt^2 / (1 + zeta dt / 2), dt in a/c_ref, zeta in c_ref/a: what multiplies a force in the update."""
    return dt * dt / (1.0 + 0.5 * zeta * dt)
