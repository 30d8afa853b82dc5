"""Contact for unbonded sites (``interface.contact``): a frictionless one-sided spring that keeps a site with no
bond delta0 above the substrate's surface, the segment between the two substrate sites bracketing it.

The force is checked against an independent computation on a drawn configuration; a T0 run whose bonds
cannot re-form (heal_time 5) keeps its sites above the substrate with contact and sinks without; the
contact is rank-invariant, works on the rigid substrate, and contact 0 is the paper's run bit for bit."""
import h5py
import numpy as np
import pytest

from helpers import datasets, run_cli, simulation, SMALL
from parslip.engine.kernels import budget as bg
from parslip.engine.kernels import interface as ik
from parslip.model.interface import PARTNER
from parslip.parallel.layout import PAD

# SMALL under F_N = 2, sheared (T0); a broken bond waits 5 l/c_r to re-form, longer than the run.
SINKING = {**SMALL, "load.FN": 2.0, "drive.mode": "shear", "drive.duration": 8.0, "output.snapshots": 0,
           "interface.heal_time": 5.0}


def _site_totals(row):
    """Scratch running totals per site (``loop.Budget.sites``) for a direct call of ``kernels.interface.update``."""
    return np.zeros((len(bg.SITE_TERMS), 2, len(row)))


def test_the_contact_force_is_the_documented_one_and_conserves_momentum():
    """A site with its bond cut, pressed 0.3 a into an inclined surface: the force on it is k_c (delta0 -
    d) n, normal to the segment between the substrate sites bracketing its x, and the substrate sites
    get minus that split by (1 - w, w)."""
    kc = 0.7
    sim = simulation(SMALL, **{"interface.contact": kc, "interface.heal_time": 1.0})   # no re-bonding now
    s = sim.state
    it, g = s.iface, s.iface.geom
    bx, by, tx, ty = s.level(0)
    br = g.brow
    j = (g.town0 + g.town1) // 2                           # a site in the middle of the contact
    col = j + g.tbase
    i = col - g.bbase
    it.bonds[PARTNER, j] = -1
    tx[PAD, j], ty[PAD, j] = 0.3, -0.55                   # slid 0.3 a, sunk below the rest gap
    bx[br, i], by[br, i] = 0.05, 0.1                       # the surface tilted
    bx[br, i + 1], by[br, i + 1] = -0.1, -0.2
    ik.update(0, tx[PAD], ty[PAD], bx[br], by[br], tx[PAD], ty[PAD], bx[br], by[br], it, _site_totals(tx[PAD]))
    d0 = sim.setup.law.delta0
    p0 = np.array([col + bx[br, i], by[br, i]])            # substrate sites at y = 0 (top site at rest: y = delta0)
    p1 = np.array([col + 1 + bx[br, i + 1], by[br, i + 1]])
    top = np.array([col + tx[PAD, j], d0 + ty[PAD, j]])
    e = p1 - p0
    n = np.array([-e[1], e[0]]) / np.linalg.norm(e)
    d = (top - p0) @ n
    w = (top - p0) @ e / (e @ e)
    assert 0 < w < 1 and d < d0
    f = kc * (d0 - d) * n
    assert np.allclose([it.ext_x[j], it.ext_y[j]], f, rtol=1e-12, atol=0)
    assert np.allclose([it.exb_x[i], it.exb_y[i]], -(1 - w) * f, rtol=1e-12, atol=1e-15)
    assert np.allclose([it.exb_x[i + 1], it.exb_y[i + 1]], -w * f, rtol=1e-12, atol=1e-15)
    total = np.array([it.ext_x[j] + it.exb_x[i] + it.exb_x[i + 1], it.ext_y[j] + it.exb_y[i] + it.exb_y[i + 1]])
    assert np.all(np.abs(total) < 1e-14)
    ty[PAD, j] = 0.3                                       # lifted clear of the surface: no force
    ik.update(0, tx[PAD], ty[PAD], bx[br], by[br], tx[PAD], ty[PAD], bx[br], by[br], it, _site_totals(tx[PAD]))
    assert it.ext_x[j] == 0 and it.ext_y[j] == 0


def _drop(path) -> float:
    """The deepest any top site went below its height at the drive's start, over the frames (a)."""
    with h5py.File(path, "r") as f:
        uy = f["interface/uy"][...]
        l = float(f["interface/x"].shape[0])               # l = top_cols a
    return float(-(uy - uy[0]).min() * l)


@pytest.fixture(scope="module")
def sinking(tmp_path_factory):
    """The T0 scene with contact 0 and 1 (one rank), and with contact 1 on 3 ranks."""
    from helpers import small_toml
    d = tmp_path_factory.mktemp("contact")
    sc = d / "s.toml"
    sc.write_text(small_toml(**{k: v for k, v in SINKING.items() if k not in SMALL or SMALL[k] != v}))
    out = {}
    for name, n, c in (("none", 1, 0.0), ("one", 1, 1.0), ("three", 3, 1.0)):
        out[name] = d / f"{name}.vtkhdf"
        p = run_cli(n, "run", sc, "--out", out[name], "--no-png", "--set", f"interface.contact={c}")
        assert p.returncode == 0, p.stderr
        out[name + "_stderr"] = p.stderr
    return sc, out


def test_contact_keeps_unbonded_sites_above_the_substrate(sinking):
    """heal_time 5, F_N = 2, T0: with contact 1.0 no top site ever goes 0.5 a below its starting height;
    with contact 0 the unbonded sites sink by many a, and the run says once that they can."""
    _, out = sinking
    with h5py.File(out["one"], "r") as f:
        assert f["interface/intact"][-1].sum() < f["interface/intact"].shape[1] // 2     # most bonds broken
    assert _drop(out["one"]) < 0.5
    assert _drop(out["none"]) > 5.0
    assert out["none_stderr"].count("can sink through the substrate") == 1
    assert "can sink" not in out["one_stderr"]


def test_contact_is_rank_invariant(sinking):
    """Contact 1.0 on 1 and 3 ranks: every dataset bitwise equal."""
    _, out = sinking
    one, _ = datasets(out["one"])
    three, _ = datasets(out["three"])
    assert one.keys() == three.keys()
    for name in one:
        assert one[name].tobytes() == three[name].tobytes(), name


def test_contact_on_the_rigid_substrate(sinking, tmp_path):
    """The rigid substrate's surface is flat: the sites stay above it as on the elastic one."""
    sc, _ = sinking
    out = tmp_path / "rigid.vtkhdf"
    p = run_cli(1, "run", sc, "--out", out, "--no-png", "--quiet", "--set", "interface.contact=1.0",
                "--set", "lattice.substrate='rigid'")
    assert p.returncode == 0, p.stderr
    assert _drop(out) < 0.5


def test_a_negative_contact_is_refused_with_one_line(sinking, tmp_path):
    sc, _ = sinking
    p = run_cli(1, "run", sc, "--out", tmp_path / "x.vtkhdf", "--set", "interface.contact=-1.0")
    assert p.returncode == 2
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and "interface.contact" in lines[0] and ">= 0" in lines[0]
