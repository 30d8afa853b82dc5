"""The two forms of damping (``time.damping``): the paper's body drag on every node's velocity, and the bonds'
dashpots on their rate of deformation, which leave a rigid translation alone.

A free block given a uniform velocity through the Python API keeps it under "bonds" and loses it by the
scheme's discrete factor B^n under "absolute"; "bonds" is rank-invariant and survives a restart; its
stable dt is the one ``model.damping`` states, checked against the scheme's own growth."""
import dataclasses
import math

import numpy as np
import pytest

from helpers import FREE_BLOCK, datasets, run_cli, simulation, small_toml
from parslip.engine.simulation import Simulation
from parslip.errors import NonFiniteError
from parslip.model.damping import Damping

ZETA = 0.1
V = np.array([0.013, -0.007])          # a/(a/c): the block's uniform velocity


def _translating(form: str):
    """A free block (no substrate, no load) moving at V everywhere, damping ``form``."""
    sim = simulation(FREE_BLOCK, **{"time.zeta": ZETA, "time.damping": form})
    u = np.zeros((sim.state.n_owned, 2))
    sim.set_u(u, u - V * sim.setup.dt)
    return sim


def test_bonds_damping_leaves_a_uniform_translation_alone():
    """1000 steps: every node's velocity (u(n) - u(n-1))/dt is still V to 1e-12."""
    sim = _translating("bonds")
    sim.run(until=1000)
    v = (sim.u - sim.u_prev) / sim.setup.dt
    assert np.max(np.abs(v - V)) < 1e-12


def test_absolute_damping_brakes_it_by_the_discrete_factor():
    """1000 steps: the velocity is V B^n, B = (1 - zeta dt/2)/(1 + zeta dt/2), to 1e-10 relative, and
    B^n is within 1e-4 of exp(-zeta t)."""
    sim = _translating("absolute")
    n = 1000
    sim.run(until=n)
    dt = sim.setup.dt
    b = (1 - ZETA * dt / 2) / (1 + ZETA * dt / 2)
    v = (sim.u - sim.u_prev) / dt
    assert np.max(np.abs(v - V * b ** n)) < 1e-10 * np.abs(V).max()
    assert abs(b ** n - math.exp(-ZETA * n * dt)) < 1e-4
    assert b ** n < 0.99                          # a brake there is something to see of


@pytest.mark.parametrize("safety,grows", [(0.98, False), (1.03, True)])
def test_the_bonds_damping_limit_on_dt_is_the_schemes(safety, grows):
    """A free block of the block's material with zeta = 0.5 (beta/dt of order 1): just below the stated
    limit a perturbation of the highest mode stays bounded over 3000 steps, just above it grows."""
    sc = {**FREE_BLOCK, "lattice.top_rows": 6, "lattice.top_cols": 12, "time.zeta": 0.5, "time.damping": "bonds"}
    ref = simulation(sc)
    st = ref.setup
    assert st.dt_limit == pytest.approx(Damping(0.5, "bonds").dt_limit(st.omega_max, [st.material.kn_top]))
    assert st.dt_limit < 2 / st.omega_max
    sim = Simulation(dataclasses.replace(st, dt=safety * st.dt_limit))     # past the limit derive() refuses
    nd = sim.state.nodes()
    checker = np.where((nd["row"] + nd["col"]) % 2 == 0, 1e-6, -1e-6)
    sim.set_u(np.stack([checker, checker], axis=1))
    try:
        sim.run(until=3000)
        size = float(np.abs(sim.u).max())
    except NonFiniteError:                        # the engine stops a run that grew without bound
        size = math.inf
    assert (size > 1e-3) == grows


def test_bonds_damping_on_one_and_three_ranks_and_through_a_restart(tmp_path):
    """SMALL with the bonds' damping: bitwise the same on 1 and 3 ranks, and stopped at 3 l/c_r then
    continued to 6 (2 ranks) bitwise the run made at once."""
    sc = tmp_path / "s.toml"
    sc.write_text(small_toml(**{"time.damping": "bonds", "output.snapshots": 0, "checkpoint.every": 1.0}))
    runs = {}
    for name, n, extra in (("one", 1, ()), ("three", 3, ()), ("half", 2, ("--set", "drive.duration=3.0")),
                           ("absolute", 1, ("--set", "time.damping='absolute'"))):
        runs[name] = tmp_path / f"{name}.vtkhdf"
        p = run_cli(n, "run", sc, "--out", runs[name], "--no-png", "--quiet", *extra, timeout=900)
        assert p.returncode == 0, p.stderr
    p = run_cli(1, "run", sc, "--out", runs["half"], "--no-png", "--quiet", "--restart", str(runs["half"]) + ".ckpt.h5")
    assert p.returncode == 0, p.stderr
    one, attrs = datasets(runs["one"])
    assert attrs["status"] == "complete"
    for other in ("three", "half"):
        got, _ = datasets(runs[other])
        for name in one:
            if name.startswith("interface/"):
                assert got[name].tobytes() == one[name].tobytes(), (other, name)
    absolute, _ = datasets(runs["absolute"])                    # the form does change the run
    assert not np.array_equal(absolute["interface/ux"], one["interface/ux"])


def test_a_damping_form_other_than_the_two_is_refused_with_one_line(tmp_path):
    sc = tmp_path / "s.toml"
    sc.write_text(small_toml())
    p = run_cli(1, "run", sc, "--out", tmp_path / "x.vtkhdf", "--set", "time.damping='relative'")
    assert p.returncode == 2
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and "time.damping" in lines[0] and "'bonds'" in lines[0]
