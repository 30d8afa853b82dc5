"""Stiff and extreme scenes: each runs stably with the numbers theory gives, or is refused before the run.

Substrate stiffness, damping, drive speed, normal load, interface, Poisson
ratio, ten million steps, and a run that blows up: every case on a small
lattice, compared with an analytic result or an independent computation
(the assembled stiffness matrix of ``model.stability``, a dense linear
solve, the damped oscillator's recurrence).
"""
import math
import os

import h5py
import numpy as np
import pytest

from helpers import SMALL, row_nodes, scene, simulation, small_toml
from parslip.cli import main
from parslip.io.contract import read_status
from parslip.model.lattice import BOTTOM, TOP
from parslip.model.physics import DENSITY, ROW_HEIGHT
from parslip.model.stability import bulk_omega2, stiffness_matrix
from parslip.scene.derive import derive

# No load, no drive, no breaking: the lattice is the linear system of the assembled stiffness.
STILL = {"drive.mode": "none", "load.ramp": 0.0, "load.settle": 0.0, "load.FN": 0.0, "interface.delta_b": 100.0,
         "output.snapshots": 0, "drive.duration": 1.0}


def _info(capture, tmp_path, *argv, **over):
    """`parslip info` of SMALL with overrides: (exit code, stdout, stderr); ``capture`` is capsys or capfd."""
    sc = tmp_path / "s.toml"
    sc.write_text(small_toml(**over))
    code = main(["info", str(sc), *argv])
    cap = capture.readouterr()
    return code, cap.out, cap.err


def _stiffness(st):
    """The assembled stiffness of the scene (model.stability), restricted to the free DOFs, dense."""
    mat, s = st.material, st.scene
    K, free = stiffness_matrix(st.lattice, [mat.kn_bottom, mat.kn_top], [mat.kt_bottom, mat.kt_top],
                               s["interface.kx"], s["interface.ky"])
    return K, free


def _mean_gap(sim):
    """Mean y_ij of the interface bonds (a), by column: the top row against the substrate row below it."""
    lat = sim.setup.lattice
    bx, by, tx, ty = sim.state.level(sim.n)
    s = sim.state.owned_sites()
    gap = sim.setup.scene["interface.delta0"] + ty[1, s]
    if not lat.rigid:
        g = sim.state.iface.geom
        cols = np.arange(s.start, s.stop) + g.tbase - g.bbase
        gap = gap - by[g.brow, cols]
    return gap


# ------------------------------------------------------------------------------------- substrate stiffness --

def test_stiff_substrate_time_step_follows_the_infinite_lattice_and_the_cost_grows(capsys, tmp_path):
    """k_n from 100 to 1e4: omega_max^2 ~ 6 k_n (the infinite central-force lattice's maximum, at the zone
    edge's M point; a 4-row substrate with a fixed row reaches 91 % of it), so dt ~ 1/sqrt(k_n): a 100x
    stiffer substrate takes a 10x shorter step, and `parslip info` reports 10x the node updates."""
    cost = {}
    dts = {}
    for kn in (100.0, 1e3, 1e4):
        st = derive(scene(**{**SMALL, "material.bottom_kn": kn}))
        assert 0.85 <= st.omega_max ** 2 / (6 * kn) <= 1 + 2 * 0.3 / (6 * kn), (kn, st.omega_max)
        dts[kn] = st.dt
        code, out, _ = _info(capsys, tmp_path, **{"material.bottom_kn": kn})
        assert code == 0
        line = next(x for x in out.splitlines() if x.startswith("cost"))
        cost[kn] = float(line.split()[1])
        assert cost[kn] == pytest.approx(st.lattice.n_nodes * st.n_steps, rel=1e-3)
    assert bulk_omega2(1e4, 0.0) == pytest.approx(6e4, rel=1e-9)        # the infinite lattice's maximum
    assert dts[1e4] / dts[100.0] == pytest.approx(0.1, rel=0.01)
    assert dts[1e3] / dts[100.0] == pytest.approx(math.sqrt(0.1), rel=0.01)
    assert cost[1e4] / cost[100.0] == pytest.approx(10.0, rel=0.02)
    assert cost[1e3] / cost[100.0] == pytest.approx(math.sqrt(10.0), rel=0.02)
    # test_engine.py::test_rigid_substrate_is_the_stiff_limit: the results converge to the rigid substrate.


# ------------------------------------------------------------------------------------------------ damping --

@pytest.mark.parametrize("zeta", [0.0, 10.0, 1e3, 1e6])
def test_every_mode_decays_as_the_damped_oscillator_for_any_zeta(zeta):
    """A normal mode of the assembled stiffness (omega^2 an eigenvalue of K) stays that mode under damped
    Verlet, its amplitude following (1 + c) a(n+1) = (2 - omega^2 dt^2) a(n) - (1 - c) a(n-1), c = zeta dt/2,
    whose roots have |lambda| < 1 for every omega dt < 2 and every zeta > 0 (product (1-c)/(1+c); p(+-1) > 0).
    Checked on the highest and the lowest mode, including zeta dt >> 1, where the highest mode's roots
    approach +-1 again (slow, but decaying)."""
    sim = simulation(SMALL, **{**STILL, "time.zeta": zeta})
    st = sim.setup
    K, free = _stiffness(st)
    w2, V = np.linalg.eigh(K[free][:, free].toarray())
    # omega_max is the largest eigenvalue's root rounded up to 24 significant bits (model.stability).
    assert np.sqrt(w2[-1]) * (1 - 1e-12) <= st.omega_max <= np.sqrt(w2[-1]) * (1 + 2.0 ** -23)
    dt, c = st.dt, 0.5 * zeta * st.dt
    # The amplification factor of every mode of this lattice, and of any 0 < omega dt < 2 at this zeta
    # (omega = 0, a free translation, keeps its root 1: it has nothing to decay to).
    radius = max(np.abs(np.roots([1 + c, -(2 - dt * dt * w), 1 - c])).max() for w in w2)
    assert radius < 1 if zeta > 0 else radius == pytest.approx(1.0, abs=1e-12)
    if zeta > 0:
        assert all(np.abs(np.roots([1 + c, -(2 - x * x), 1 - c])).max() < 1 for x in np.linspace(1e-3, 1.999, 400))
    A = 1e-3
    for mode in (-1, 0):
        phi = np.zeros(K.shape[0])
        phi[free] = V[:, mode]
        sim = simulation(SMALL, **{**STILL, "time.zeta": zeta})
        sim.set_u((A * phi).reshape(-1, 2))
        a_old, a = A, A
        for _ in range(300):
            sim.step()
            a_old, a = a, ((2 - dt * dt * w2[mode]) * a - (1 - c) * a_old) / (1 + c)
        u = sim.u.ravel()
        got = u @ phi
        assert abs(got - a) <= 1e-10 * A, (mode, got, a)
        assert np.abs(u - got * phi).max() <= 1e-10 * A                  # still the one mode


def test_heavy_damping_energy_decreases_every_step_by_the_damping_work():
    """zeta = 1e3 (zeta dt = 77) from a random strain: the modified energy of Verlet,
    H(n) = (|u(n) - u(n-1)|^2 + dt^2 u(n).K u(n-1)) / (2 dt^2), positive for omega_max dt < 2,
    falls each step by exactly zeta |u(n+1) - u(n-1)|^2 / (4 dt): bounded and monotone."""
    zeta = 1e3
    sim = simulation(SMALL, **{**STILL, "time.zeta": zeta})
    st = sim.setup
    K, free = _stiffness(st)
    rng = np.random.default_rng(3)
    u = np.zeros(K.shape[0])
    u[free] = 0.01 * rng.standard_normal(free.sum())
    sim.set_u(u.reshape(-1, 2))
    dt = st.dt

    def H(a, b):
        return (np.sum((a - b) ** 2) + dt * dt * a @ (K @ b)) / (2 * dt * dt)
    prev, cur = sim.u_prev.ravel(), sim.u.ravel()
    h = [H(cur, prev)]
    for _ in range(2000):
        sim.step()
        new = sim.u.ravel()
        hn = H(new, cur)
        assert hn == pytest.approx(h[-1] - zeta * np.sum((new - prev) ** 2) / (4 * dt), rel=1e-9, abs=1e-15)
        assert 0 <= hn <= h[-1] * (1 + 1e-12)
        h.append(hn)
        prev, cur = cur, new
    assert h[-1] < 0.9 * h[0]                  # it really decays


def test_info_warns_where_damping_freezes_the_block(capsys, tmp_path):
    """Warned when the damping time 1/zeta is below H/c_s, the time a shear wave needs to cross the block's
    height (SMALL: H = 3 sqrt(3)/2 and c_s = 1/0.911 in the default unit c_r, so above zeta = 0.423); the
    default zeta = 0.1 is not."""
    h = 3 * ROW_HEIGHT
    cs = derive(scene(**SMALL)).material.c_s
    for zeta, warned in ((0.1, False), (0.95 * cs / h, False), (1.05 * cs / h, True), (1e3, True)):
        code, out, _ = _info(capsys, tmp_path, **{"time.zeta": zeta})
        assert code == 0
        assert ("H/c_s" in out) == warned, (zeta, out)
    assert "block is frozen" in out and f"c_s/H = {cs / h:.3g}" in out


def test_bonds_damping_freezes_only_where_its_dashpots_outrun_the_height_wave(capsys, tmp_path):
    """Under time.damping = "bonds" the slowest wave across the height (omega = pi c_s/H) is damped at
    beta omega^2 = zeta pi^2 c_s^2/(k_n H^2): the warning comes above zeta = k_n H/(pi^2 c_s) (0.674 on SMALL),
    not at the body drag's c_s/H = 0.42, and never at the paper's zeta."""
    h = 3 * ROW_HEIGHT
    mat = derive(scene(**SMALL)).material
    limit = mat.kn_top * h / (math.pi ** 2 * mat.c_s)
    assert limit > 1.5 * mat.c_s / h                   # the two forms' thresholds are apart
    for zeta, warned in ((0.1, False), (1.05 * mat.c_s / h, False), (0.95 * limit, False), (1.05 * limit, True)):
        code, out, _ = _info(capsys, tmp_path, **{"time.zeta": zeta, "time.damping": "bonds"})
        assert code == 0
        assert ("block is frozen" in out) == warned, (zeta, out)
    assert f"k_n H/(pi^2 c_s) = {limit:.3g}" in out


# ------------------------------------------------------------------------------------------- drive speed --

def test_slowest_drive_moves_its_face_exactly_and_warns_that_nothing_breaks(capsys, tmp_path):
    """v0 = 1e-5 c_r runs: the driven rear face moves v0 t to round-off, no bond breaks, and info says the
    drive is too short to break one (v0 T below sqrt(delta_b^2 - delta0^2))."""
    over = {"drive.v0": 1e-5, "lattice.substrate": "rigid", "output.snapshots": 0}
    sim = simulation(SMALL, **over)
    st = sim.setup
    sim.run(until=st.n_drive_start)
    rear = row_nodes(sim, 0)[0]
    x_eq = sim.u[rear, 0]
    sim.run()
    assert sim.u[rear, 0] - x_eq == pytest.approx(st.v0 * st.n_drive * st.dt, rel=1e-9)
    assert sim.counters[0] == 0
    code, out, _ = _info(capsys, tmp_path, **over)
    assert code == 0 and "expect no rupture" in out


@pytest.mark.parametrize("substrate", ["rigid", "elastic"])
def test_fast_drive_runs_and_the_far_edge_waits_for_the_longitudinal_wave(substrate):
    """v0 = 0.5 c_r push: stable; inertia dominates, so the front edge stays put (< 1 % of the rear face's
    motion) until a longitudinal wave from the driven face can have reached it, at (l - a)/c_l, and moves
    clearly (> 5 %) by 1.2 times that."""
    sim = simulation(SMALL, **{"output.snapshots": 0, "drive.v0": 0.5, "drive.duration": 1.0,
                               "lattice.substrate": substrate})
    st = sim.setup
    sim.run(until=st.n_drive_start)
    front = row_nodes(sim, 0)[-1]
    x0 = sim.u[front, 0]
    t_arrive = (SMALL["lattice.top_cols"] - 1) / st.material.c_l
    seen = {}
    for f in (0.9, 1.2):
        sim.run(until=st.n_drive_start + int(f * t_arrive / st.dt))
        t = (sim.n - st.n_drive_start) * st.dt
        seen[f] = (sim.u[front, 0] - x0) / (st.v0 * t)
    assert abs(seen[0.9]) < 0.01 and seen[1.2] > 0.05, seen
    sim.run()
    assert np.isfinite(sim.u).all() and np.abs(sim.u).max() < st.v0 * st.n_drive * st.dt + 1.0


def test_fast_drive_is_warned_in_info_and_in_the_run_log(capfd, tmp_path):
    code, out, _ = _info(capfd, tmp_path, **{"drive.v0": 0.05})
    assert code == 0 and "inertia dominates" not in out
    code, out, _ = _info(capfd, tmp_path, **{"drive.v0": 0.2})
    assert code == 0 and "drive.v0 = 0.2 c_r: fast" in out and "inertia dominates" in out
    sc = tmp_path / "fast.toml"
    sc.write_text(small_toml(**{"drive.v0": 0.2, "drive.duration": 0.2, "lattice.substrate": "rigid",
                                "output.snapshots": 0}))
    assert main(["run", str(sc), "--out", str(tmp_path / "fast.vtkhdf"), "--quiet", "--no-png"]) == 0
    err = capfd.readouterr().err
    assert any("WARNING" in x and "inertia dominates" in x for x in err.splitlines()), err


def _refused(capsys, tmp_path, frags, **over):
    code, _, err = _info(capsys, tmp_path, **over)
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and lines[0].startswith("parslip: error: "), err
    for frag in frags:
        assert frag in lines[0], (frag, lines[0])


@pytest.mark.parametrize("mode,wave", [("push", "c_l"), ("pull", "c_l"), ("shear", "c_s")])
def test_drive_at_the_speed_of_its_wave_is_refused(capsys, tmp_path, mode, wave):
    """A drive launches a wave carrying the strain v0/c (c_l for a face moved along its normal, c_s along
    itself): v0 >= c is refused, naming the limit; just below it runs (no warning about the limit)."""
    st = derive(scene(**SMALL))
    c = st.material.c_l if wave == "c_l" else st.material.c_s
    lim = c / st.material.c_r                           # 1.79254 and 1.09770 c_r at nu = 0.2
    _refused(capsys, tmp_path, ["drive.v0", wave, f"{lim:.6g}", "accepted: 0 < drive.v0 <"],
             **{"drive.mode": mode, "drive.v0": 1.001 * lim})
    code, _, err = _info(capsys, tmp_path, **{"drive.mode": mode, "drive.v0": 0.99 * lim})
    assert code == 0, err


def test_drive_moving_its_face_as_far_as_the_runaway_check_is_refused(capsys, tmp_path):
    """With a rigid substrate's long step, a push just below c_l would move its face more than 0.5 a per
    step, which the engine's health check stops as a blow-up: refused, naming the largest v0 at this dt."""
    st = derive(scene(**{**SMALL, "lattice.substrate": "rigid"}))
    v0 = 0.6 / st.dt / st.material.c_r
    assert v0 < st.material.c_l / st.material.c_r
    _refused(capsys, tmp_path, ["drive.v0", "per step", f"{0.5 / st.dt / st.material.c_r:.4g}"],
             **{"lattice.substrate": "rigid", "drive.v0": v0})


# ------------------------------------------------------------------------------------------- normal load --

@pytest.mark.parametrize("share", [0.0, 0.5, 0.99])
def test_normal_load_up_to_the_closing_load(share):
    """At rest the springs carry F_N: mean gap = delta0 - F_N/(N k_y), down to 1 % of delta0 at 0.99 of
    the closing load N k_y delta0 = 24 x 0.3 x 0.5 = 3.6 (rigid substrate: exact statics, quick to settle).
    The gaps spread about their mean: the block's top row sits half a spacing ahead of its interface row
    (alternating row offsets), so the load tilts it and its front sinks more; near the limit the front
    gap is below zero, but no bond is compressed to delta_b and none breaks."""
    N, ky, d0 = 24, 0.3, 0.5
    FN = share * N * ky * d0
    sim = simulation(SMALL, **{"lattice.substrate": "rigid", "drive.mode": "none", "load.FN": FN,
                               "load.settle": 40.0, "drive.duration": 0.01, "output.snapshots": 0})
    sim.run(until=sim.setup.n_drive_start)
    assert np.abs(sim.u - sim.u_prev).max() / sim.setup.dt < 1e-10                 # at rest
    gap = _mean_gap(sim)
    assert gap.mean() == pytest.approx(d0 - FN / (N * ky), abs=1e-10)
    assert sim.counters[0] == 0 and gap.min() > -sim.setup.scene["interface.delta_b"]
    assert gap[-1] == gap.min()                                         # the front sinks most
    if share <= 0.5:
        assert (gap > 0).all()


def test_info_warns_where_single_gaps_may_close(capsys, tmp_path):
    for share, warned in ((0.45, False), (0.99, True)):
        code, out, _ = _info(capsys, tmp_path, **{"load.FN": share * 3.6})
        assert code == 0 and ("single gaps spread" in out) == warned, (share, out)
        assert f"mean gap at rest {0.5 * (1 - share):.4g} a" in out


@pytest.mark.parametrize("share", [1.0, 1.5])
def test_normal_load_at_or_beyond_the_closing_load_is_refused(capsys, tmp_path, share):
    _refused(capsys, tmp_path, ["load.FN", "closes the interface gap", "N k_y delta0 = 3.6"],
             **{"load.FN": share * 3.6})


def test_normal_load_on_an_elastic_substrate_near_the_limit():
    """The same statics through the elastic substrate: the fixed row AB pushes back with F_N."""
    N, ky, d0 = 24, 0.3, 0.5
    FN = 0.95 * N * ky * d0
    sim = simulation(SMALL, **{"drive.mode": "none", "load.FN": FN, "load.settle": 30.0, "drive.duration": 0.01,
                               "output.snapshots": 0})
    sim.run(until=sim.setup.n_drive_start)
    assert _mean_gap(sim).mean() == pytest.approx(d0 - FN / (N * ky), abs=1e-9)
    K, free = _stiffness(sim.setup)
    f = K @ sim.u.ravel()            # minus the internal force on each DOF: at AB, what the support exerts
    fixed_y = np.flatnonzero(~free)[1::2]
    assert f[fixed_y].sum() == pytest.approx(FN, rel=1e-8)


# ------------------------------------------------------------------------------------------------ interface --

@pytest.mark.parametrize("side", [-1, 1])
def test_bond_breaks_exactly_at_delta_b_barely_above_delta0(side):
    """delta_b = delta0 + 1e-3: a bond breaks when its length reaches delta_b.  The block shifted rigidly by
    d in x (no bulk force) has bonds of length sqrt(d^2 + delta0^2): all break for d 1e-6 above
    sqrt(delta_b^2 - delta0^2) = 0.0316, none 1e-6 below."""
    d0, db = 0.5, 0.501
    sim = simulation(SMALL, **{**STILL, "interface.delta_b": db, "lattice.substrate": "rigid"})
    d = math.sqrt(db * db - d0 * d0) * (1 + side * 1e-6)
    u = np.zeros((sim.state.n_owned, 2))
    u[:, 0] = d
    sim.set_u(u)
    sim.step()
    assert sim.counters[0] == (24 if side > 0 else 0)


def test_barely_breakable_interface_runs_and_slides():
    """delta_b = delta0 + 1e-3 under SMALL's push: stable; the first bond to go is the rear one (site 0,
    at the driven face), bonds break and re-form, and the interface slides with the drive."""
    sim = simulation(SMALL, **{"output.snapshots": 0, "interface.delta_b": 0.501})
    st = sim.setup
    sim.run(until=st.n_drive_start)
    assert sim.counters[0] == 0                          # compressed bonds are shorter than delta0
    while sim.counters[0] == 0:
        sim.step()
    assert list(np.flatnonzero(sim.state.owned_partner() < 0)) == [0]
    sim.run()
    assert sim.counters[0] > 24 and sim.counters[1] > 24
    slide = st.v0 * st.n_drive * st.dt
    ux = sim.u[row_nodes(sim, 0), 0]
    assert np.isfinite(sim.u).all() and 0.5 * slide < ux.mean() < 1.1 * slide


def test_stiff_interface_springs_set_the_time_step():
    """k_x, k_y 100x the defaults on a rigid substrate: omega_max includes the springs.  Weyl's inequality
    bounds omega_max^2 between the stiffest spring's diagonal, k_y + K_yy of an interface node (a Rayleigh
    quotient), and omega_max^2 of the block alone + k_y; dt = 0.9 x 2/omega_max, and a run at 0.99 of the
    limit stays bounded."""
    kx, ky = 10.0, 30.0
    st = derive(scene(**{**SMALL, "lattice.substrate": "rigid", "interface.kx": kx, "interface.ky": ky}))
    soft = derive(scene(**{**SMALL, "lattice.substrate": "rigid"}))
    block = derive(scene(**{**SMALL, "lattice.bottom_rows": 0, "load.FN": 0.0}))     # the block alone, free
    mat = st.material
    kyy = 2 * (0.75 * (mat.kn_top - mat.kt_top) + mat.kt_top) + 2 * mat.kt_top     # two up bonds, two in-row
    assert ky + kyy <= st.omega_max ** 2 <= block.omega_max ** 2 + ky + 1e-9
    # springs shorten it (0.674 x with the block in the default unit c_r, 0.63 x in c_s)
    assert st.dt == pytest.approx(0.9 * 2 / st.omega_max) and st.dt < 0.7 * soft.dt
    sim = simulation(SMALL, **{"lattice.substrate": "rigid", "interface.kx": kx, "interface.ky": ky,
                               "time.safety": 0.99, "time.zeta": 0.0, "drive.duration": 2.0, "output.snapshots": 0})
    sim.run()
    assert np.isfinite(sim.u).all() and np.abs(sim.u).max() < 5.0


def test_frictionless_interface_slides_the_block_compressed_by_the_damping_drag_alone():
    """k_x = 0 (and F_N = 0): the interface carries no shear, its recorded traction sxy is 0; the rear
    bond breaks the step its length sqrt(x^2 + y^2) reaches delta_b; the block slides with the drive and
    only the damping drag zeta v0 per node resists it: a row of length L shortens by
    zeta v0 L^2 / (2 h E) (uniaxial stress zeta v0 (L - x) / h, Young's modulus of the Born lattice
    E = rho 4 mu'(lambda' + mu')/(lambda' + 2 mu'), lambda' = 3/8 (k_n - k_t), mu' = 3/8 (k_n + k_t))."""
    sim = simulation(SMALL, **{"output.snapshots": 0, "interface.kx": 0.0, "load.FN": 0.0,
                               "lattice.substrate": "rigid"})
    st = sim.setup
    mat = st.material
    sim.run(until=st.n_drive_start)
    rear = row_nodes(sim, 0)
    db = st.scene["interface.delta_b"]

    def rear_length():
        x, y = sim.u[rear[0]]
        return math.hypot(x, st.scene["interface.delta0"] + y)        # the rigid partner stays at its site
    lengths = [rear_length()]
    while sim.counters[0] == 0:
        sim.step()
        lengths.append(rear_length())
    # The step from n broke it, looking at u(n) (lengths[-2]); at u(n - 1) it still held.
    assert lengths[-3] < db <= lengths[-2]
    assert list(np.flatnonzero(sim.state.owned_partner() < 0)) == [0]
    sim.run()
    assert np.all(sim.frames.sxy == 0.0)
    lam, mu = 0.375 * (mat.kn_top - mat.kt_top), 0.375 * (mat.kn_top + mat.kt_top)
    E = DENSITY * 4 * mu * (lam + mu) / (lam + 2 * mu)
    L = SMALL["lattice.top_cols"] - 1
    shortening = st.scene["time.zeta"] * st.v0 * L * L / (2 * ROW_HEIGHT * E)
    ux = sim.u[rear, 0]
    assert ux[0] - ux[-1] == pytest.approx(shortening, rel=0.1)
    assert ux.min() > st.v0 * st.n_drive * st.dt - 2 * shortening        # the whole block came along


# ------------------------------------------------------------------------------------------- Poisson ratio --

@pytest.mark.parametrize("nu,model", [(0.25, "plane_strain"), (1 / 3, "plane_stress")])
def test_poisson_limit_where_k_t_vanishes_runs(nu, model):
    """At nu = 1/4 (plane strain) or 1/3 (plane stress), c_l^2 = 3 c_s^2, so k_t = c_s^2 - c_l^2/3 = 0 and
    c_r/c_s = sqrt(2 - 2/sqrt(3)), the Poisson solid's Rayleigh speed; SMALL's push runs, bounded."""
    sim = simulation(SMALL, **{"material.nu": nu, "material.model": model, "output.snapshots": 0})
    mat = sim.setup.material
    assert abs(mat.kt_top) < 1e-15
    assert mat.c_l / mat.c_s == pytest.approx(math.sqrt(3.0), rel=1e-14)
    assert mat.c_r / mat.c_s == pytest.approx(math.sqrt(2 - 2 / math.sqrt(3)), rel=1e-12)
    sim.run()
    assert np.isfinite(sim.u).all() and np.abs(sim.u).max() < 5.0 and sim.counters[0] > 0


@pytest.mark.parametrize("nu,model,frag", [(0.2501, "plane_strain", "k_t < 0"),
                                           (0.34, "plane_stress", "out of range")])
def test_poisson_ratio_beyond_the_limit_is_refused(capsys, tmp_path, nu, model, frag):
    _refused(capsys, tmp_path, ["material.nu", str(nu), frag], **{"material.nu": nu, "material.model": model})


# -------------------------------------------------------------------------------------------------- long run --

@pytest.mark.slow
def test_ten_million_steps_keep_the_fixed_row_and_the_load():
    """10^7 steps of a 16-node lattice (a 2 x 4 block on a 2-row substrate) under F_N with damping: the
    fixed row AB stays exactly zero throughout, the energy never rises once the load is on, and at the
    end the state is the static solution of the assembled stiffness (dense solve), the reaction at AB
    is F_N and the mean gap delta0 - F_N/(N k_y), to round-off."""
    tiny = {"lattice.top_rows": 2, "lattice.top_cols": 4, "lattice.bottom_rows": 2, "lattice.bottom_cols": 4,
            "drive.mode": "none", "load.FN": 0.3, "load.ramp": 1.0, "load.settle": 0.0, "output.snapshots": 0}
    st = derive(scene(**tiny, **{"drive.duration": 1.0}))
    duration = (10 ** 7 - st.n_ramp) * st.dt / st.t_unit
    sim = simulation(tiny, **{"drive.duration": duration, "output.interface_dt": duration})
    st = sim.setup
    assert 10 ** 7 <= st.n_steps <= 10 ** 7 + 1
    K, free = _stiffness(st)
    f = np.zeros(K.shape[0])
    nodes = sim.state.nodes()
    loaded = np.flatnonzero((nodes["block"] == TOP) & (nodes["row"] == 1))
    f[2 * loaded + 1] = -st.scene["load.FN"] / 4
    u_static = np.zeros(K.shape[0])
    u_static[free] = np.linalg.solve(K[free][:, free].toarray(), f[free])
    fixed = (nodes["block"] == BOTTOM) & (nodes["row"] == 0)

    def energy():
        u, v = sim.u.ravel(), sim.u_prev.ravel()
        return (np.sum((u - v) ** 2) / st.dt ** 2 + u @ (K @ v)) / 2 - f @ (u + v) / 2
    sim.run(until=st.n_ramp + 1)
    e = [energy()]
    for k in range(1, 11):
        sim.run(until=min(k * 10 ** 6, st.n_steps))
        assert np.all(sim.u[fixed] == 0.0) and np.all(sim.u_prev[fixed] == 0.0)
        e.append(energy())
        assert e[-1] <= e[-2] + 1e-14 * abs(e[0])         # a few ulps of the energy sum itself
    assert sim.n == st.n_steps
    assert np.abs(sim.u.ravel() - u_static).max() < 1e-12
    reaction = (K @ sim.u.ravel())[2 * np.flatnonzero(fixed) + 1].sum()    # what AB exerts, upward
    assert reaction == pytest.approx(st.scene["load.FN"], rel=1e-12)
    assert _mean_gap(sim).mean() == pytest.approx(0.5 - 0.3 / (4 * 0.3), abs=1e-12)
    assert e[-1] == pytest.approx(-f @ u_static / 2, rel=1e-12)          # the static energy, -f.u/2


# ---------------------------------------------------------------------------------------------------- runaway --

def test_runaway_stops_early_through_the_command_line_and_keeps_a_readable_file(capsys, tmp_path, monkeypatch):
    """A stale omega_max cache entry (1/1.2 of the true value, as a cache written for other stiffnesses
    might hold) makes the run's dt 8 % above the real limit, 2/omega_max.  The state then grows without
    bound; the health check stops the run within 256 steps with exit code 3, naming the step, the node
    and the likely cause, and the file keeps status 'failed: ...' and the frames written before it."""
    from parslip.io import cache
    monkeypatch.setenv("PARSLIP_CACHE_DIR", str(tmp_path / "cache"))
    over = {"load.FN": 0.0, "load.ramp": 0.0, "load.settle": 0.0, "drive.duration": 3.0, "output.snapshots": 0}
    st = derive(scene(**{**SMALL, **over}))                  # computes the true value (and caches it)
    lat, mat = st.lattice, st.material
    b, t = lat.blocks
    key = cache.key(top=[t.rows, t.cols], bottom=[b.rows, b.cols], substrate=lat.substrate,
                    kn=[mat.kn_bottom, mat.kn_top], kt=[mat.kt_bottom, mat.kt_top], kx=0.1, ky=0.3)
    assert cache.lookup(key) == (st.omega_max, "lanczos")
    cache.store(key, (st.omega_max / 1.2, "lanczos"))
    sc = tmp_path / "stale.toml"
    sc.write_text(small_toml(**over))
    out = tmp_path / "stale.vtkhdf"
    code = main(["run", str(sc), "--out", str(out), "--quiet", "--no-png"])
    err = capsys.readouterr().err
    assert code == 3, err
    line = next(x for x in err.splitlines() if x.startswith("parslip: run failed"))
    assert "grew without bound" in line or "non-finite" in line, line
    for frag in ("at step", "node", "block, row", "likely cause", "time step"):
        assert frag in line, (frag, line)
    step = int(line.split("at step ")[1].split()[0])
    stale = derive(scene(**{**SMALL, **over}))
    assert stale.dt > st.dt_limit and step < stale.n_steps and step % 256 == 0
    with h5py.File(out, "r") as f:
        assert read_status(f).startswith("failed: state ")
        k = int(f["interface"].attrs["frames_written"])
        assert 1 <= k < stale.n_frames
        steps = np.round(f["interface/time"][:k] * stale.t_unit / stale.dt)
        assert steps[-1] < step
        assert np.all(f["interface/ux"][0] == 0.0)          # the drive's start: at rest, no load
    assert os.path.getsize(out) > 0
