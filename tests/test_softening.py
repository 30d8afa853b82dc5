"""Slip-weakening bonds (``interface.softening``), checked against the law's own numbers.

A single bond pulled quasi-statically in shear at y = delta0 takes, up to its break, the law's fracture energy
Gamma = tau_p (x_b + D_c) / 2 (``model.interface``: x_b = sqrt(delta_b^2 - delta0^2), tau_p = k_x x_b; no
residual without contact friction), and closer as the pull's step shrinks; the same energy is what the
break event says the weakening took.  The unloading path is the secant to the origin, k_y is untouched while
the bond weakens, and a re-formed bond starts undamaged.  In a lattice run the budget closes with the
weakening's term, on any rank count and through a restart, and D_c = 0 (also set by a patch) is the paper's
run bit for bit.
"""
import math

import numpy as np
import pytest

from helpers import SMALL, datasets, run_small, simulation
from parslip.engine.kernels import budget as bg
from parslip.engine.kernels import interface as ik
from parslip.model.interface import PARTNER, PEAK, SLIPPED, SPENT
from parslip.parallel.layout import PAD

DC = 0.3


class Bond:
    """One interface bond of a SMALL lattice driven by hand: every node at rest but the top site ``j``, whose
    displacement is set before each call of the interface kernel (``kernels.interface.update``)."""

    def __init__(self, **over):
        self.sim = simulation(SMALL, **{"interface.softening": DC, "load.FN": 0.0, **over})
        s = self.sim.state
        self.it, g = s.iface, s.iface.geom
        self.j = (g.town0 + g.town1) // 2
        bx, by, tx, ty = s.level(0)
        self.row = tx[PAD], ty[PAD], bx[g.brow], by[g.brow]
        self.prev = tuple(a.copy() for a in self.row)
        self.sites = np.zeros((len(bg.SITE_TERMS), 2, len(self.row[0])))
        self.n = 0

    def move(self, ux, uy=0.0):
        """Put the top site at (ux, uy) and take one step of the interface kernel; the force on the top node."""
        tx, ty = self.row[0], self.row[1]
        for a, b in zip(self.prev, self.row):
            a[:] = b
        tx[self.j], ty[self.j] = ux, uy
        ik.update(self.n, *self.row, *self.prev, self.it, self.sites)
        self.n += 1
        return float(self.it.ext_x[self.j]), float(self.it.ext_y[self.j])

    @property
    def bonded(self) -> bool:
        return self.it.bonds[PARTNER, self.j] >= 0


def _pull(h: float) -> tuple[float, float, dict]:
    """A bond pulled in x at y = delta0 in steps of h, to its break: the work done on it in damped Verlet's
    form (each step's force times (x(n+1) - x(n-1))/2, the energy budget's), the peak it caught, and its break
    event (m c^2)."""
    b = Bond()
    work, k = 0.0, 0
    while b.bonded:
        k += 1
        f, _ = b.move(k * h)
        if b.bonded:
            work -= f * h
    ev = b.it.events
    last = int(ev.count[0]) - 1
    assert ev.kind[last] == 1
    return work, float(b.it.bonds[PEAK, b.j]), {"energy": float(ev.energy[last]),
                                                 "dissipated": float(ev.dissipated[last])}


def test_a_bond_pulled_in_shear_takes_the_laws_gamma_up_to_its_break():
    """k_x = 0.1, delta_b = 0.7, delta0 = 0.5, D_c = 0.3: Gamma = k_x x_b (x_b + D_c)/2 = 0.0193485 m c^2.  The
    work to the break is k_x s_p (s_p + D_c)/2 of the peak s_p the pull caught (the first step past x_b), to
    1e-7 (the break falls between two steps): the law's envelope and secant exactly.  With steps h = x_b/(m +
    1/2) the catch comes h/2 late, so the work is off Gamma by k_x (2 x_b + D_c) h / 4 to first order: a
    quarter at a quarter of the step, and within 1e-4 of Gamma at m = 16000 (h = 3.1e-5 a).  The break
    event's dissipated energy (the staggered sum the budget keeps) is that work, to round-off, and its stored
    energy 0: a bond weakened to a zero residual keeps nothing."""
    xb = math.sqrt(0.7 ** 2 - 0.5 ** 2)
    gamma = 0.1 * xb * (xb + DC) / 2
    assert gamma == pytest.approx(0.0193485, abs=1e-7)
    errors = []
    for m in (4000, 16000):
        h = xb / (m + 0.5)
        work, peak, event = _pull(h)
        assert peak == pytest.approx(xb + h / 2, abs=1e-6 * h)
        assert work == pytest.approx(0.1 * peak * (peak + DC) / 2, rel=1e-7)
        errors.append((work - gamma) / gamma)
        assert errors[-1] == pytest.approx(0.1 * (2 * xb + DC) * h / 4 / gamma, rel=1e-3)
        assert event["dissipated"] == pytest.approx(work, rel=1e-9)
        assert abs(event["energy"]) < 1e-12
    assert errors[1] == pytest.approx(errors[0] / 4, rel=1e-3) and errors[1] < 1e-4


def test_the_weakening_unloads_along_the_secant_and_keeps_k_y():
    """Half-way down the weakening, the bond's force is the secant's -k_d x at every x back to 0 and on
    reloading (no damage grows below the envelope, so the weakening took no more), while its normal force
    is -k_y (y - delta0) whatever its damage."""
    b = Bond()
    xb = math.sqrt(0.7 ** 2 - 0.5 ** 2)
    x = 0.0
    while x < xb + DC / 2:
        x += 1e-3
        b.move(x)
    peak = float(b.it.bonds[PEAK, b.j])
    slipped = float(b.it.bonds[SLIPPED, b.j])
    spent = float(b.it.bonds[SPENT, b.j])
    assert peak == pytest.approx(xb, abs=1e-3) and slipped == pytest.approx(DC / 2, abs=1e-3)
    kd = 0.1 * peak * (1 - slipped / DC) / (peak + slipped)          # tau_m / (s_p + delta_m)
    for u in np.linspace(x, 0.05, 7).tolist() + np.linspace(0.1, x, 5).tolist():
        fx, fy = b.move(u, 0.02)
        assert fx == pytest.approx(-kd * u, rel=1e-12)
        assert fy == pytest.approx(-0.3 * 0.02, rel=1e-12)
        assert b.bonded and float(b.it.bonds[SLIPPED, b.j]) == slipped
    assert float(b.it.bonds[SPENT, b.j]) == pytest.approx(spent, abs=1e-9)


def test_a_re_formed_bond_starts_undamaged():
    """A bond pulled to its break and brought back over its substrate site re-forms with no peak, no slip
    past it and nothing spent, and holds with k_x again."""
    b = Bond()
    x = 0.0
    while b.bonded:
        x += 1e-3
        b.move(x)
    b.move(0.0)
    assert b.bonded
    assert b.it.bonds[PEAK, b.j] == 0 and b.it.bonds[SLIPPED, b.j] == 0 and b.it.bonds[SPENT, b.j] == 0
    fx, _ = b.move(0.05)
    assert fx == pytest.approx(-0.1 * 0.05, rel=1e-12)


def _run(tmp_path, name, n=1, **sets):
    return run_small(tmp_path, name, n, **sets)[1]


def _kept(path) -> dict:
    data, attrs = datasets(path)
    assert attrs["status"] == "complete", attrs["status"]
    return {k: v for k, v in data.items() if k.startswith(("interface/", "energy/"))}


SHEARED = {"drive.mode": "shear", "drive.v0": 0.05, "output.energy": "checked"}


def test_a_zero_weakening_patch_is_the_papers_run(tmp_path):
    """D_c = 0 set by a patch over the whole contact (so the weakening's code runs, and every bond breaks at
    its peak through it) writes every /interface and /energy dataset of the default run bit for bit, the new
    ones (/interface/softening, /energy/softening, the events' dissipated) all zero."""
    a = _kept(_run(tmp_path, "plain", **SHEARED))
    b = _kept(_run(tmp_path, "patched", **SHEARED, **{"interface.patch": [{"x": [0.0, 1.0], "softening": 0.0}]}))
    assert a.keys() == b.keys() and (a["interface/events/kind"] == 1).sum() > 10
    for name in a:
        assert a[name].tobytes() == b[name].tobytes(), name
    assert not a["energy/softening"].any() and not a["interface/events/dissipated"].any()


def test_the_budget_closes_with_weakening_bonds(tmp_path):
    """D_c = 0.3 under a fast shear (every bond weakens and breaks, many re-form): the checked residual stays
    below 1e-9 of the drive's work, the weakening took energy, and each break after a weakening says so."""
    e = _kept(_run(tmp_path, "soft", **SHEARED, **{"interface.softening": DC}))
    work = abs(e["energy/work_drive"][-1])
    assert work > 0 and np.nanmax(np.abs(e["energy/residual"])) < 1e-9 * work
    assert e["energy/softening"][-1] > 0.01 * work
    breaks = e["interface/events/kind"] == 1
    assert (e["interface/events/dissipated"][breaks] > 0).sum() > 10
