"""Friction on the contact (``interface.contact_friction``): a stick spring of the contact's stiffness along the
substrate's surface, its force bounded by mu times the contact's normal force.

A site dragged over a flat substrate sticks (the spring's force k_c x) until its force reaches mu k_c p, then
slides with exactly that force at every step, without a sign flip, and unloads and reverses elastically; a
block sliding on its contact under F_N loses mu F_N per unit slip; a block held below that does not creep;
with contact, friction and weakening on, the budget closes on 1 and 3 ranks to the same bits, and the run
continues from a checkpoint on another rank count bit for bit.
"""
import numpy as np
import pytest

from helpers import SMALL, datasets, run_cli, run_small, simulation
from parslip.engine.kernels import budget as bg
from parslip.engine.kernels import interface as ik
from parslip.model.interface import PARTNER, STICK
from parslip.parallel.layout import PAD

KC, MU = 0.3, 0.4


class FreeSite:
    """Top site ``j`` of a SMALL lattice at rest with its bond cut (it never re-bonds), pressed ``p`` into the flat
    substrate, moved by hand in x, one call of the interface kernel per move."""

    def __init__(self, p: float):
        self.sim = simulation(SMALL, **{"interface.contact": KC, "interface.contact_friction": MU,
                                        "interface.heal_time": 1e3, "load.FN": 0.0})
        s = self.sim.state
        self.it, g = s.iface, s.iface.geom
        self.j = (g.town0 + g.town1) // 2
        self.it.bonds[PARTNER, self.j] = -1
        bx, by, tx, ty = s.level(0)
        self.row = tx[PAD], ty[PAD], bx[g.brow], by[g.brow]
        self.row[1][self.j] = -p
        self.prev = tuple(a.copy() for a in self.row)
        self.sites = np.zeros((len(bg.SITE_TERMS), 2, len(self.row[0])))
        self.n = 0

    def move(self, ux: float) -> tuple[float, float]:
        for a, b in zip(self.prev, self.row):
            a[:] = b
        self.row[0][self.j] = ux
        ik.update(self.n, *self.row, *self.prev, self.it, self.sites)
        self.n += 1
        return float(self.it.ext_x[self.j]), float(self.it.ext_y[self.j])


def test_a_dragged_site_sticks_then_slides_at_mu_times_its_normal_force():
    """Pressed p = 0.1 a into the substrate (normal force k_c p = 0.03): dragged in x it holds with -k_c x up
    to x = mu p, then slides with -mu k_c p exactly at every step; turned back, its force rises elastically
    by k_c per unit of travel through zero to +mu k_c p, and slides back with that; its normal force is k_c p
    throughout; the friction it dissipates sliding is mu k_c p per unit slip."""
    p, h = 0.1, 1e-3
    site = FreeSite(p)
    cap = MU * KC * p
    forward = [site.move(k * h) for k in range(1, 101)]
    xs = np.arange(1, 101) * h
    fx = np.array([f for f, _ in forward])
    stick = xs < MU * p - 1e-12
    np.testing.assert_allclose(fx[stick], -KC * xs[stick], rtol=1e-12)
    np.testing.assert_allclose(fx[~stick], -cap, rtol=1e-12)
    np.testing.assert_allclose([f for _, f in forward], KC * p, rtol=1e-12)
    rubbed = site.sites[bg.S_FRICTION].sum()
    slid = xs[-1] - MU * p
    assert rubbed == pytest.approx(cap * slid, rel=1e-3)
    back = np.array([site.move(xs[-1] - k * h)[0] for k in range(1, 101)])
    turn = np.arange(1, 101) * h < 2 * MU * p - 1e-12
    np.testing.assert_allclose(back[turn], -cap + KC * np.arange(1, 101)[turn] * h, rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(back[~turn], cap, rtol=1e-12)
    assert np.all(np.diff(np.sign(back)) >= 0)                     # one sign change, no chatter
    assert float(site.it.bonds[STICK, site.j]) == pytest.approx(-MU * p, rel=1e-12)


def test_out_of_contact_a_site_has_no_friction():
    """Lifted off the substrate a free site feels nothing, and its stick spring is gone."""
    site = FreeSite(0.1)
    site.move(0.08)
    site.row[1][site.j] = 0.2
    assert site.move(0.1) == (0.0, 0.0)
    assert site.it.bonds[STICK, site.j] == 0


# SMALL pushed at 0.02 c_r on a contact of k_c = k_y = 0.3 with friction 0.4: every bond weakened to its residual
# at 0.5-0.6 l/c_r (a nucleation over the whole contact), none re-forms, so the block slides on friction.
SLIDER = {"drive.v0": 0.02, "drive.duration": 10.0, "output.energy": "checked", "interface.contact": KC,
          "interface.contact_friction": MU, "interface.heal_time": 100.0, "interface.nucleation.kind": "time",
          "interface.nucleation.x": [0.0, 1.0], "interface.nucleation.start": 0.5,
          "interface.nucleation.duration": 0.1}


def test_a_block_sliding_on_its_contact_loses_mu_f_n_per_unit_slip(tmp_path):
    """Once every bond has handed over to friction the block slides at the drive's speed: the friction it
    dissipates per unit slip of its interface row is mu F_N (to 2 %), the interface's mu reads mu (to 2 %),
    every site's shear traction keeps its sign, and the checked budget closes to 1e-6 of the drive's work."""
    _, out = run_small(tmp_path, "slider", **SLIDER)
    data, _ = datasets(out)
    t, e = data["interface/time"], data["energy/friction"]
    assert not data["interface/intact"][t > 1.0].any()
    late = t > 4.0
    slip = data["interface/ux"][late].mean(axis=1) * SMALL["lattice.top_cols"]     # a
    assert slip[-1] - slip[0] > 1.0
    assert (e[late][-1] - e[late][0]) / (slip[-1] - slip[0]) == pytest.approx(MU * 1.0, rel=0.02)
    assert np.all(np.abs(data["interface/mu"][late] - MU) < 0.02 * MU)
    assert np.all(data["interface/sxy"][late] > 0)
    work = abs(data["energy/work_drive"][-1])
    assert np.nanmax(np.abs(data["energy/residual"])) < 1e-6 * work


def test_a_block_held_below_mu_f_n_does_not_creep(tmp_path):
    """Pushed through soft springs (0.05 per driven node: nearly a constant force) to a mean shear traction of
    0.008 rho c_r^2, about half of mu F_N's share per site, and held there, its bonds then all hand over to
    friction: the block stops within the stick springs' elastic reach and then does not move: over the last
    3 l/c_r its interface row moves less than 1e-6 a, and friction takes nothing more."""
    held = {**SLIDER, "drive.spring": 0.05, "drive.duration": 14.0, "drive.prestress.tau0": 0.008,
            "drive.prestress.settle": 1.0, "interface.nucleation.start": 0.0}
    _, out = run_small(tmp_path, "held", **held)
    data, _ = datasets(out)
    t = data["interface/time"]
    assert not data["interface/intact"][-1].any()
    slip = data["interface/ux"].mean(axis=1) * SMALL["lattice.top_cols"]
    end = t > t[-1] - 3.0
    assert np.ptp(slip[end]) < 1e-6
    assert np.ptp(data["energy/friction"][end]) < 1e-9 * abs(data["energy/work_drive"][-1])


# Contact, friction and weakening together under a fast shear (bonds break and re-form).
ALL_ON = {"drive.mode": "shear", "drive.v0": 0.05, "drive.duration": 6.0, "output.energy": "checked",
          "interface.contact": KC, "interface.contact_friction": MU, "interface.softening": 0.3,
          "checkpoint.every": 1.0}


def test_the_budget_with_contact_friction_and_weakening_closes_the_same_on_any_rank_count(tmp_path):
    """1 and 3 ranks write the same bits (every /interface and /energy dataset), the residual stays below 1e-6
    of the drive's work with friction and weakening taking their parts; a run stopped at 3 l/c_r on 2 ranks
    and continued on 3 from its checkpoint writes them too (the stick springs and the damage travel)."""
    sc, one = run_small(tmp_path, "all", 1, **ALL_ON)
    _, three = run_small(tmp_path, "all", 3, **ALL_ON)
    out = tmp_path / "restarted.vtkhdf"
    p = run_cli(2, "run", sc, "--out", out, "--no-png", "--quiet", "--set", "drive.duration=3.0", timeout=200)
    assert p.returncode == 0, p.stderr
    p = run_cli(3, "run", sc, "--out", out, "--no-png", "--quiet", "--restart", str(out) + ".ckpt.h5", timeout=200)
    assert p.returncode == 0, p.stderr
    a = datasets(one)[0]
    names = [n for n in a if n.startswith(("interface/", "energy/"))]
    for other in (three, out):
        b = datasets(other)[0]
        for name in names:
            assert a[name].tobytes() == b[name].tobytes(), (other.name, name)
    work = abs(a["energy/work_drive"][-1])
    assert np.nanmax(np.abs(a["energy/residual"])) < 1e-6 * work
    assert a["energy/friction"][-1] > 1e-3 * work and a["energy/softening"][-1] > 1e-3 * work
