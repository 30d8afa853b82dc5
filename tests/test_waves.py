"""Wave speeds measured in the lattice against theory.

Bulk: P and S pulses in a free block travel at c_l and c_s of Eq. 2.2.
Surface: a Rayleigh-type packet on a free surface travels at the Born
continuum's own surface-wave speed (about 0.947 c_s at nu = 0.2), not at the
classical Rayleigh speed (0.911 c_s) that the paper uses for units: the k_t
term resists rigid rotation.
"""
import numpy as np
import pytest

from helpers import FREE_BLOCK, row_nodes, set_field, simulation
from parslip.model.physics import (Material, born_stiffness, born_surface_ratio, born_wave_speeds, cl_over_cs,
                             rayleigh_ratio)


def test_rayleigh_ratio_matches_cubic():
    """Classical Rayleigh root against the cubic in eta = (c_r/c_s)^2:
    eta^3 - 8 eta^2 + (24 - 16/r^2) eta - 16 (1 - 1/r^2) = 0, r = c_l/c_s."""
    for nu in (0.0, 0.2, 0.25):
        r = cl_over_cs(nu, "plane_strain")
        roots = np.roots([1, -8, 24 - 16 / r**2, -16 * (1 - 1 / r**2)])
        eta = min(z.real for z in roots if abs(z.imag) < 1e-12 and 0 < z.real < 1)
        assert rayleigh_ratio(r) == pytest.approx(np.sqrt(eta), abs=1e-10)
    assert rayleigh_ratio(cl_over_cs(0.2, "plane_strain")) == pytest.approx(0.9110, abs=1e-4)


def test_eq_2_2_round_trip_and_kt():
    kn, kt = born_stiffness(np.sqrt(8 / 3), 1.0)
    assert (kn, kt) == pytest.approx((7 / 3, 1 / 9))
    assert born_wave_speeds(kn, kt) == pytest.approx((np.sqrt(8 / 3), 1.0))
    m = Material.from_scene(0.2, "plane_stress", "c_r", 100.0, 0.0)
    assert m.c_r == pytest.approx(1.0)
    assert m.c_l / m.c_s == pytest.approx(np.sqrt(2 / 0.8))
    # No k_t term: the Born surface wave is the classical one.
    assert born_surface_ratio(1.0, 0.0) == pytest.approx(rayleigh_ratio(np.sqrt(3)), abs=1e-9)


def _pulse_speed(comp):
    """Speed of a one-way Gaussian plane pulse along the middle row of a tall free block."""
    rows, cols, w, x0 = 100, 200, 6.0, 60.0
    sim = simulation(FREE_BLOCK, **{"lattice.top_rows": rows, "lattice.top_cols": cols})
    st, mat = sim.setup, sim.setup.material
    c_launch = mat.c_l if comp == 0 else mat.c_s

    def g(x):
        return np.exp(-((x - x0) / w) ** 2)
    set_field(sim, lambda x, y: (g(x), 0 * x) if comp == 0 else (0 * x, g(x)))
    u_prev = sim.u_prev
    u_prev[:, comp] = g(sim.state.nodes()["x"] + c_launch * st.dt)   # moving right
    sim.set_u(sim.u, u_prev)
    mid = row_nodes(sim, rows // 2)
    xs = sim.state.nodes()["x"][mid]
    # Stop before waves from the free top/bottom surfaces reach the middle row.
    n = int(0.4 * rows * np.sqrt(3) / 2 / mat.c_l / st.dt)
    ts, ps = [], []
    for k in range(0, n + 1, 5):
        prof = sim.u[mid, comp]
        i = int(np.argmax(prof))
        a, b, c = prof[i - 1:i + 2]
        ts.append(k * st.dt)
        ps.append(xs[i] + 0.5 * (a - c) / (a - 2 * b + c))
        sim.run(until=sim.n + 5)
    assert ps[-1] - ps[0] > 15           # it really travelled
    return np.polyfit(ts, ps, 1)[0], mat


@pytest.mark.parametrize("comp", [0, 1], ids=["P", "S"])
def test_bulk_wave_speed(comp):
    v, mat = _pulse_speed(comp)
    expected = born_wave_speeds(mat.kn_top, mat.kt_top)[comp]      # Eq. 2.2 inverted
    assert v == pytest.approx(expected, rel=0.02)


def test_surface_wave_speed_is_the_born_lattice_s_own():
    """Phase velocity of a surface packet of wavelength 40 a on a free strip.

    The packet starts with the Born continuum's surface-mode shape; the
    phase of its Fourier component at k = 2 pi / 40 on the top row gives the
    phase velocity.  Lattice dispersion at lambda = 40 a is below 0.3 %.
    """
    rows, cols, lam, env, x0 = 80, 600, 40.0, 40.0, 150.0
    sim = simulation(FREE_BLOCK, **{"lattice.top_rows": rows, "lattice.top_cols": cols})
    st, m = sim.setup, sim.setup.material
    c, cl, cs = m.c_surface_born, m.c_l, m.c_s
    eta = 0.75 * m.kt_top
    mu = cs**2 - eta
    lamb = cl**2 - 2 * mu
    qp, qs = np.sqrt(1 - c**2 / cl**2), np.sqrt(1 - c**2 / cs**2)
    M = np.empty((2, 2), complex)
    for col, (ux, uy, q) in enumerate(((1j, qp, qp), (qs, -1j, qs))):
        M[0, col] = (mu + eta) * q * ux + (mu - eta) * 1j * uy
        M[1, col] = (lamb + 2 * mu) * q * uy + lamb * 1j * ux
    A = np.linalg.svd(M)[2].conj()[-1]           # free-surface null vector (A_p, A_s)
    k = 2 * np.pi / lam
    nd = sim.state.nodes()
    ytop = nd["y"].max()

    def mode(t):
        x, yy = nd["x"] - c * t, nd["y"] - ytop
        ep, es, ph = np.exp(qp * k * yy), np.exp(qs * k * yy), np.exp(1j * k * x)
        envl = np.exp(-((x - x0) / env) ** 2)
        ux = (A[0] * 1j * ep + A[1] * qs * es) * ph
        uy = (A[0] * qp * ep - 1j * A[1] * es) * ph
        return np.real(ux) * envl, np.real(uy) * envl

    sim.set_u(np.stack(mode(0.0), axis=1), np.stack(mode(-st.dt), axis=1))
    top = row_nodes(sim, rows - 1)
    xs = nd["x"][top]
    n = int((cols - x0 - 2.5 * env) / c / st.dt)
    ts, phase = [], []
    for i in range(0, n, 10):
        ts.append(i * st.dt)
        phase.append(np.angle(np.sum(sim.u[top, 1] * np.exp(-1j * k * xs))))
        sim.run(until=sim.n + 10)
    ts, phase = np.array(ts), np.unwrap(phase)
    late = ts > 0.3 * ts[-1]                      # after body waves shed at the start leave the surface
    v = -np.polyfit(ts[late], phase[late], 1)[0] / k
    assert v == pytest.approx(m.c_surface_born, rel=0.006)
    assert m.c_surface_born / m.c_s == pytest.approx(0.9475, abs=5e-4)
    assert v / m.c_r > 1.03                       # clearly not the classical Rayleigh speed
