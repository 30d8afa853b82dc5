"""How the two damping forms (``time.damping``) attenuate a wave against its frequency, measured.

A free block (no substrate, no load) is set in one of its own standing waves: an eigenvector phi of the
assembled stiffness (``model.stability.stiffness_matrix``) as u(0) = u(-dt), at rest.  The run's
projection q_n = phi . u(n) is then sampled every h = s dt.  For one mode the scheme makes the samples obey a
two-term recurrence q_{k+1} = p1 q_k + p0 q_{k-1} exactly, with roots r e^{+-i theta}: its least-squares fit
over the run measures both the decay rate -ln(r)/h (amplitude, per unit time) and the frequency
omega = theta/h, from the run alone.  Theory (``model.damping``):

- "absolute": r^2 = B = (1 - zeta dt/2)/(1 + zeta dt/2) whatever the mode, so the rate is
  -ln(B)/(2 dt) = zeta/2 (1 + O(zeta^2 dt^2)).
- "bonds": the dashpots are beta K on the free block's bulk bonds (beta = zeta/k_n), so every eigenmode
  decays alone at beta omega^2/2, omega its own (measured) frequency.  The scheme's O(dt) departures
  (|lambda|^2 = 1 - beta omega^2 dt exactly, and Verlet's theta = 2 arcsin(omega dt/2)) are below
  beta omega^2 dt/2 + (omega dt)^2/6 < 1.5 % for omega dt <= 0.25 here, hence the 3 % tolerance.
"""
import numpy as np
import pytest

from helpers import FREE_BLOCK, simulation
from parslip.model.stability import stiffness_matrix

ZETA = 0.1            # c/a
DT = 0.06             # a/c: omega dt <= 0.25 over the modes below
SAMPLES = 40          # samples of the projection per run
OMEGAS = (0.2, 1.0, 2.0, 3.5)   # c/a: the block's modes nearest these, from its longest waves to ~2 a
SCENE = {**FREE_BLOCK, "lattice.top_rows": 6, "lattice.top_cols": 40, "time.zeta": ZETA, "time.dt": DT}


def _modes(scene: dict = SCENE):
    """The free block's eigenpairs (omega^2, phi as (n_nodes, 2) in global id order), its k_n and c_s."""
    st = simulation(scene).setup
    m = st.material
    k, _ = stiffness_matrix(st.lattice, [m.kn_bottom, m.kn_top], [m.kt_bottom, m.kt_top], 0.0, 0.0)
    w2, vec = np.linalg.eigh(k.toarray())
    return w2, vec, m.kn_top, m.c_s


def _stride(omega2: float, dt: float) -> int:
    """Steps per sample turning a wave of frequency sqrt(omega2) by ~1/2 radian."""
    return max(1, round(0.5 / (np.sqrt(omega2) * dt)))


def _nearest(w2: np.ndarray, omega: float) -> int:
    """The index of the eigenpair whose frequency is nearest ``omega``."""
    return int(np.argmin(np.abs(np.sqrt(np.maximum(w2, 0.0)) - omega)))


def measure(scene: dict, form: str, phi: np.ndarray, steps: int, stride: int = 1):
    """(rate, omega) of the projection on mode ``phi`` of a run started in it at rest (1/time, 1/time),
    sampled every ``stride`` steps (the recurrence holds for any stride; one that turns the wave by ~1/2
    radian per sample keeps the fit well conditioned for the slow modes)."""
    sim = simulation(scene, **{"time.damping": form})
    sim.set_u(1e-3 * phi)
    q = [float(np.sum(sim.u * phi))]
    while sim.n < steps:
        sim.run(until=sim.n + stride)
        q.append(float(np.sum(sim.u * phi)))
    q = np.array(q)
    (p1, p0), *_ = np.linalg.lstsq(np.stack([q[1:-1], q[:-2]], axis=1), q[2:], rcond=None)
    r = np.sqrt(-p0)
    h = stride * sim.setup.dt
    return -np.log(r) / h, np.arccos(p1 / (2 * r)) / h


@pytest.fixture(scope="module")
def measured():
    w2, vec, kn, _ = _modes()
    out = []
    for target in OMEGAS:
        i = _nearest(w2, target)
        stride = _stride(w2[i], DT)
        phi = vec[:, i].reshape(-1, 2)
        out.append({form: measure(SCENE, form, phi, SAMPLES * stride, stride) for form in ("absolute", "bonds")})
    return out, ZETA / kn


def test_absolute_damping_takes_every_wave_at_the_same_rate(measured):
    """Rate -ln(B)/(2 dt) (= zeta/2 to 1e-4) for every mode, to 1e-6 relative."""
    rows, _ = measured
    b = (1 - ZETA * DT / 2) / (1 + ZETA * DT / 2)
    for row in rows:
        assert row["absolute"][0] == pytest.approx(-np.log(b) / (2 * DT), rel=1e-6)
    assert -np.log(b) / (2 * DT) == pytest.approx(ZETA / 2, rel=1e-4)


def test_bonds_damping_takes_a_wave_at_beta_omega_squared_over_two(measured):
    """Rate beta omega^2/2 with omega the mode's measured frequency, to 3 %; from the longest wave to the
    shortest the rate grows more than 100-fold, and the long waves keep far more than under "absolute",
    where the same mode oscillates at sqrt(omega^2 - zeta^2/4) (to 1 % in omega^2)."""
    rows, beta = measured
    rates = []
    for row in rows:
        rate, omega = row["bonds"]
        assert rate == pytest.approx(beta * omega ** 2 / 2, rel=0.03)
        # the same wave under either form: the body drag lowers its frequency to sqrt(omega^2 - zeta^2/4)
        assert row["absolute"][1] ** 2 + ZETA ** 2 / 4 == pytest.approx(omega ** 2, rel=0.01)
        rates.append(rate)
    assert rates[-1] > 100 * rates[0]
    assert rates[0] < 0.05 * rows[0]["absolute"][0]


def table(wavelengths=(200.0, 50.0, 20.0, 10.0, 5.0, 2.5), dt: float = 0.05):
    """The docs' table: the paper's block (10 x 100, free) at zeta = 0.1 and ``dt``; for each shear wavelength
    lambda (a) the mode nearest omega = 2 pi c_s / lambda, its measured omega and rates (c/a) under both forms,
    beta omega^2/2, and the 1/e attenuation length c_s / rate (a) of a shear wave of that frequency."""
    scene = {**FREE_BLOCK, "time.zeta": ZETA, "time.dt": dt}
    w2, vec, kn, c_s = _modes(scene)
    print("| lambda (a) | omega (c_r/a) | absolute | bonds | beta omega^2/2 | L absolute (a) | L bonds (a) |")
    for lam in wavelengths:
        i = _nearest(w2, 2 * np.pi * c_s / lam)
        stride = _stride(w2[i], dt)
        phi = vec[:, i].reshape(-1, 2)
        (ra, _), (rb, om) = (measure(scene, f, phi, SAMPLES * stride, stride) for f in ("absolute", "bonds"))
        print(f"| {2 * np.pi * c_s / om:.1f} | {om:.4f} | {ra:.4f} | {rb:.3g} | {ZETA / kn * om ** 2 / 2:.3g} "
              f"| {c_s / ra:.0f} | {c_s / rb:.3g} |")


if __name__ == "__main__":
    table()
