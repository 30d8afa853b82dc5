"""Static equilibrium, energy conservation and the stability limit of the time step."""
import numpy as np
import pytest

from helpers import SMALL, reference, scene, simulation
from parslip.engine.kernels import per_bond as ref_kernels
from parslip.engine.simulation import Simulation
from parslip.errors import ConfigError, NonFiniteError
from parslip.model.lattice import BOTTOM, FIXED, TOP
from parslip.scene.derive import derive


def _gaps(sim):
    """y_ij of every interface bond (top minus bottom, a), by global id."""
    lat = sim.setup.lattice
    s = sim.state.owned_sites()
    cols = np.arange(s.start, s.stop) + sim.layout.blocks[TOP].base
    partner = sim.state.owned_partner()
    gid = {g: i for i, g in enumerate(sim.state.gid)}
    it = np.array([gid[g] for g in lat.gid(TOP, 0, cols)])
    ib = np.array([gid[g] for g in lat.gid(BOTTOM, lat.bottom.rows - 1, partner)])
    return sim.setup.scene["interface.delta0"] + sim.u[it, 1] - sim.u[ib, 1]


def test_static_compression_gap_and_reaction():
    """Under F_N the interface bonds carry the whole load:
    sum_i k_y (delta0 - gap_i) = F_N, so the mean gap is delta0 - F_N/(N k_y);
    and the fixed row AB pushes back with F_N (forces from the independent reference kernels)."""
    FN, ky, N = 2.0, 0.3, 24
    sim = simulation(SMALL, **{"drive.mode": "none", "load.FN": FN, "load.settle": 30.0, "drive.duration": 0.01})
    sim.run(until=sim.setup.n_drive_start)
    assert np.abs(sim.u - sim.u_prev).max() / sim.setup.dt < 1e-10      # at rest
    gap = _gaps(sim)
    assert gap.mean() == pytest.approx(0.5 - FN / (N * ky), abs=1e-10)
    assert np.all(gap < 0.5)                                             # every bond compressed
    ref = reference(sim)
    f = np.zeros_like(ref.u)
    ref_kernels.bulk_forces(ref.u, ref.nb, ref.block, ref.kn, ref.kt, ref.dirs, ref.n_owned, f)
    fixed = ref.kind[:ref.n_owned] == FIXED
    assert -f[:ref.n_owned][fixed, 1].sum() == pytest.approx(FN, rel=1e-9)


def _staggered_energy(ref, u_new, u_old, dt, load):
    """Energy conserved exactly by Verlet for a linear system:
    H = |u_new - u_old|^2 / (2 dt^2) + 2 V((u_new + u_old)/2) - V(u_new)/2 - V(u_old)/2,
    with V from the reference implementation's energy kernel."""
    def V(u):
        ref.u[:ref.n_owned] = u
        return ref.energy_per_node(load).sum()
    kin = 0.5 * np.sum((u_new - u_old) ** 2) / dt**2
    return kin + 2 * V(0.5 * (u_new + u_old)) - 0.5 * V(u_new) - 0.5 * V(u_old)


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
    free = ~sim.state.fixed()
    u = np.zeros((sim.state.n_owned, 2))
    u[free] = 0.02 * rng.standard_normal((free.sum(), 2))
    sim.set_u(u)
    sim.step()
    ref = reference(sim)
    h0 = _staggered_energy(ref, sim.u, sim.u_prev, dt, 1.0)
    assert h0 > 0
    dissipated = 0.0
    for _ in range(10_000):
        older = sim.u_prev
        sim.step()
        dissipated += zeta * np.sum((sim.u - older) ** 2) / (4 * dt)
    h1 = _staggered_energy(ref, sim.u, sim.u_prev, dt, 1.0)
    assert abs(h1 + dissipated - h0) / h0 < 1e-6
    assert sim.counters[0] == 0
    if zeta > 0:
        assert dissipated > 0.1 * h0               # damping really acted
    # The engine's own energy (its diagnostics kernel) agrees with the reference's.
    assert sim.energy(load=1.0) == pytest.approx(reference(sim).energy_per_node(1.0).sum(), rel=1e-12)


def _free_block_run(factor, steps):
    """A lattice with no breaking, no damping and no load, started from a random strain at dt = factor x 2/omega_max.

    Returns the largest |u| after each step, and whether the run was stopped as a runaway."""
    st = derive(scene(**{**SMALL, "drive.mode": "none", "load.ramp": 0.0, "load.settle": 0.0, "drive.duration": 0.01,
                         "time.zeta": 0.0, "interface.delta_b": 100.0, "load.FN": 0.0}))
    assert st.omega_method == "lanczos"
    st.dt = factor * st.dt_limit
    sim = Simulation(st)
    rng = np.random.default_rng(1)
    u = 1e-3 * rng.standard_normal((sim.state.n_owned, 2))
    u[sim.state.fixed()] = 0.0
    sim.set_u(u)
    amp = []
    try:
        for _ in range(steps):
            sim.step()
            amp.append(np.abs(sim.u).max())
    except NonFiniteError as e:
        return np.array(amp), str(e)
    return np.array(amp), None


def test_stability_limit_is_sharp():
    """dt = 0.99 * 2/omega_max stays bounded; 1.01 * 2/omega_max grows without bound until the run stops it."""
    below, stopped = _free_block_run(0.99, 3000)
    assert stopped is None and below.max() < 0.1
    above, stopped = _free_block_run(1.01, 3000)
    assert above.max() > 1e3 * above[0]
    assert stopped is not None and "grew without bound" in stopped


def test_divergence_is_reported_with_step_and_place():
    st = derive(scene(**{**SMALL, "drive.mode": "none", "load.ramp": 0.0, "load.settle": 0.0, "drive.duration": 50.0}))
    st.dt = 1.2 * st.dt_limit
    sim = Simulation(st)
    sim.set_u(np.full((sim.state.n_owned, 2), 1e-3))
    with pytest.raises(NonFiniteError, match=r"(non-finite|grew without bound)[^0-9]* at step \d+ .*node \d+ "
                                             r"\((top|bottom) block, row \d+, column \d+"):
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
