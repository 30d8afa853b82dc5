"""Static equilibrium, energy conservation and the stability limit of the time step."""
import numpy as np
import pytest

from helpers import SMALL, simulation
from parslip.errors import ConfigError
from parslip.errors import NonFiniteError
from parslip.scene.derive import derive
from parslip.model.lattice import FIXED
from helpers import scene


def _gaps(sim):
    s = sim.own_sites
    it = sim.top_node[s]
    ib = sim.bot_node[sim.partner[s] - sim.bot_g0]
    return sim.delta0 + sim.u[it, 1] - sim.u[ib, 1]


def test_static_compression_gap_and_reaction():
    """Under F_N the interface bonds carry the whole load:
    sum_i k_y (delta0 - gap_i) = F_N, so the mean gap is delta0 - F_N/(N k_y);
    and the fixed row AB pushes back with F_N."""
    FN, ky, N = 2.0, 0.3, 24
    sim = simulation(SMALL, **{"drive.mode": "none", "load.FN": FN, "load.settle": 30.0, "drive.duration": 0.01})
    sim.run(until=sim.setup.n_drive_start)
    assert np.abs(sim.u - sim.u_prev).max() / sim.setup.dt < 1e-10      # at rest
    gap = _gaps(sim)
    assert gap.mean() == pytest.approx(0.5 - FN / (N * ky), abs=1e-10)
    assert np.all(gap < 0.5)                                             # every bond compressed
    # Reaction of the fixed row = minus the bond force on it.
    f = np.zeros_like(sim.u)
    from parslip.engine import kernels
    kernels.bulk_forces(sim.u, sim.nb, sim.block, sim.kn, sim.kt, sim.dirs, sim.n_owned, f)
    fixed = sim.kind[:sim.n_owned] == FIXED
    assert -f[:sim.n_owned][fixed, 1].sum() == pytest.approx(FN, rel=1e-9)


def _V(sim, u):
    keep = sim.u.copy()
    sim.u[:] = u
    e = sim.energy_per_node().sum()
    sim.u[:] = keep
    return e


def _staggered_energy(sim, u_new, u_old):
    """Energy conserved exactly by Verlet for a linear system:
    H = |u_new - u_old|^2 / (2 dt^2) + 2 V((u_new + u_old)/2) - V(u_new)/2 - V(u_old)/2."""
    dt = sim.setup.dt
    kin = 0.5 * np.sum((u_new - u_old) ** 2) / dt**2
    return kin + 2 * _V(sim, 0.5 * (u_new + u_old)) - 0.5 * _V(sim, u_new) - 0.5 * _V(sim, u_old)


@pytest.mark.parametrize("zeta", [0.0, 0.05])
def test_energy_balance(zeta):
    """zeta = 0: energy drifts by < 1e-6 (relative) over 1e4 steps, from a random
    initial strain with a suddenly applied load and no breaking.
    zeta > 0: the energy lost equals the damping work, sum zeta |u(n+1) - u(n-1)|^2 / (4 dt)."""
    sim = simulation(SMALL, **{"drive.mode": "none", "load.ramp": 0.0, "load.settle": 0.0,
                               "interface.delta_b": 100.0, "time.zeta": zeta, "drive.duration": 1e-3,
                               "load.FN": 3.0})
    dt = sim.setup.dt
    rng = np.random.default_rng(7)
    free = sim.kind != FIXED
    sim.u[free] = 0.02 * rng.standard_normal((free.sum(), 2))
    sim.u_prev[:] = sim.u
    sim.step()
    h0 = _staggered_energy(sim, sim.u, sim.u_prev)
    assert h0 > 0
    dissipated = 0.0
    for _ in range(10_000):
        older = sim.u_prev.copy()
        sim.step()
        dissipated += zeta * np.sum((sim.u - older) ** 2) / (4 * dt)
    h1 = _staggered_energy(sim, sim.u, sim.u_prev)
    assert abs(h1 + dissipated - h0) / h0 < 1e-6
    assert sim.counters[0] == 0
    if zeta > 0:
        assert dissipated > 0.1 * h0               # damping really acted


def _free_block_run(factor, steps):
    sim = simulation(SMALL, **{"drive.mode": "none", "load.ramp": 0.0, "load.settle": 0.0, "drive.duration": 0.01,
                               "time.zeta": 0.0, "interface.delta_b": 100.0, "load.FN": 0.0})
    st = sim.setup
    assert st.omega_method == "lanczos"
    st.dt = factor * st.dt_limit
    rng = np.random.default_rng(1)
    sim.u[:sim.n_owned] = 1e-3 * rng.standard_normal((sim.n_owned, 2))
    sim.u[sim.kind == FIXED] = 0.0
    sim.u_prev[:] = sim.u
    amp = []
    for _ in range(steps):
        sim.step()
        amp.append(np.abs(sim.u).max())
    return np.array(amp), sim


def test_stability_limit_is_sharp():
    """dt = 0.99 * 2/omega_max stays bounded; 1.01 * 2/omega_max grows without bound."""
    below, _ = _free_block_run(0.99, 3000)
    above, _ = _free_block_run(1.01, 600)
    assert below.max() < 0.1
    assert above[-1] > 1e3 * above[0]


def test_divergence_is_reported_with_step_and_place():
    sim = simulation(SMALL, **{"drive.mode": "none", "load.ramp": 0.0, "load.settle": 0.0, "drive.duration": 50.0})
    sim.setup.dt = 1.2 * sim.setup.dt_limit
    sim.u[:sim.n_owned] = 1e-3
    with pytest.raises(NonFiniteError, match=r"non-finite at step \d+ .* at node \d+ \((top|bottom) block, row"):
        sim.run()


def test_dt_above_limit_is_refused():
    st = derive(scene(**SMALL))
    with pytest.raises(ConfigError, match=r"time\.dt = .*above the stability limit"):
        derive(scene(**{**SMALL, "time.dt": 1.001 * st.dt_limit}))
    assert derive(scene(**{**SMALL, "time.dt": 0.999 * st.dt_limit})).dt == pytest.approx(0.999 * st.dt_limit)
    # The paper's a/c_l criterion would allow a step far beyond the real limit.
    assert st.dt_paper > 5 * st.dt_limit


@pytest.mark.parametrize("over", [
    {"material.bottom_kn": 1e4},                              # a 100x stiffer substrate
    {"material.nu": 0.25},                                    # k_t = 0 exactly
    {"material.nu": -0.5, "material.model": "plane_stress"},  # auxetic block
    {"interface.ky": 50.0, "interface.kx": 50.0},             # interface stiffer than the block
])
def test_extreme_materials_stay_bounded_at_safety_099(over):
    """The dt rule follows the stiffest part of the system: stable at 0.99 of the limit."""
    sim = simulation(SMALL, **{"time.safety": 0.99, "drive.duration": 2.0, "time.zeta": 0.0, **over})
    st = sim.setup
    assert st.dt == pytest.approx(0.99 * 2 / st.omega_max)
    sim.run()
    assert np.isfinite(sim.u).all() and np.abs(sim.u).max() < 5.0
    if over.get("material.bottom_kn") == 1e4:
        # omega_max^2 of an infinite lattice of k_n is 6 k_n; a 4-row block stays below it.
        assert 1.0 <= st.dt_limit / (2 / np.sqrt(6e4 + 2 * 0.3)) < 1.1
