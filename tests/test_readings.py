"""The scene keys of the paper's open readings: each does what its help says, and the default is the old path."""
import numpy as np
import pytest

from helpers import SMALL, scene, simulation
from parslip.engine.kernels import budget as bg
from parslip.engine.kernels import interface as ik
from parslip.errors import ConfigError
from parslip.model.interface import PARTNER
from parslip.model.lattice import TOP
from parslip.model.physics import Material, born_stiffness, cl_over_cs
from parslip.scene.derive import derive


def _update(sim):
    """One interface update (break, claim, grant) at level 0, the unloaded reference lattice."""
    s = sim.state
    bx, by, tx, ty = s.level(0)
    g = s.iface.geom
    br = g.brow
    ik.update(0, tx[1], ty[1], bx[br], by[br], tx[1], ty[1], bx[br], by[br], s.iface,
              np.zeros((len(bg.SITE_TERMS), 2, tx.shape[1])))
    return s.iface.bonds[PARTNER].astype(np.int64)


def test_rebond_within_sets_the_largest_rebonding_length():
    """A free node lifted to a gap of 0.6 a over its free facing site: delta0 = 0.5 (the default) leaves
    it free, interface.rebond_within = 0.65 re-bonds it."""
    got = {}
    for within in (0.0, 0.65):
        sim = simulation(SMALL, **{"interface.rebond_within": within})
        s = sim.state
        j = s.iface.geom.town0 + 5
        facing = int(s.iface.bonds[PARTNER, j])
        s.iface.bonds[PARTNER, j] = -1
        _, _, _, ty = s.level(0)
        ty[1, j] = 0.1
        got[within] = (_update(sim)[j], facing)
    assert got[0.0][0] == -1
    assert got[0.65][0] == got[0.65][1]
    length = lambda **kw: derive(scene(**kw)).law.rebond_length            # noqa: E731
    assert length() == 0.5 and length(**{"interface.rebond_within": 0.8}) == 0.8


@pytest.mark.parametrize("rule, expect", [("nearest", "next"), ("facing", "none")])
def test_rebond_facing_or_nearest(rule, expect):
    """Site j free with its facing substrate site taken (bonded to site j + 1, delta_b = 1.5 keeps that
    bond) and the next site free 1.118 a away, within rebond_within = 1.2: 'nearest' takes the next site,
    'facing' waits for its own."""
    sim = simulation(SMALL, **{"interface.rebond": rule, "interface.rebond_within": 1.2, "interface.delta_b": 1.5})
    s = sim.state
    assert sim.setup.reach.link == 2
    j = s.iface.geom.town0 + 5
    q_j, q_next = int(s.iface.bonds[PARTNER, j]), int(s.iface.bonds[PARTNER, j + 1])
    s.iface.bonds[PARTNER, j] = -1
    s.iface.bonds[PARTNER, j + 1] = q_j
    p = _update(sim)
    assert p[j + 1] == q_j
    assert p[j] == (q_next if expect == "next" else -1)


@pytest.mark.parametrize("hold", ["x", "xy"])
def test_drive_hold(hold):
    """The pushed face SP: x follows x_eq + v0 t in both readings; y stays where the drive found it with
    'xy' and moves with 'x'."""
    sim = simulation(SMALL, **{"drive.mode": "push", "drive.hold": hold})
    st = sim.setup
    sim.run(until=st.n_drive_start)
    nd = sim.state.nodes()
    face = (nd["block"] == TOP) & (nd["col"] == st.lattice.top.col0)
    u0 = sim.u[face]
    sim.run()
    u1 = sim.u[face]
    shift = st.v0 * st.n_drive * st.dt
    assert u1[:, 0] - u0[:, 0] == pytest.approx(np.full(face.sum(), shift), rel=1e-9)
    moved = float(np.abs(u1[:, 1] - u0[:, 1]).max())
    if hold == "xy":
        assert moved == 0.0
    else:
        assert moved > 1e-4


def test_kn_spring_across_swaps_the_springs():
    """Eq. 2.2's k_n = 7/3, k_t = 1/9 (nu = 0.2, plane strain, c_s = 1): 'along' gives the bond's stretch
    k_n, 'across' gives it k_t, and the substrate's k_n = 100, k_t = 0 swap the same way; the units
    (c_r) stay those of nu."""
    kn, kt = born_stiffness(cl_over_cs(0.2, "plane_strain"), 1.0)
    assert (kn, kt) == pytest.approx((7 / 3, 1 / 9))
    along = derive(scene(**{"material.velocity_unit": "c_s"})).material
    across = derive(scene(**{"material.kn_spring": "across", "material.velocity_unit": "c_s"})).material
    assert (along.kn_top, along.kt_top, along.kn_bottom, along.kt_bottom) == pytest.approx((kn, kt, 100.0, 0.0))
    assert (across.kn_top, across.kt_top, across.kn_bottom, across.kt_bottom) == pytest.approx((kt, kn, 0.0, 100.0))
    assert across.c_r == along.c_r
    with pytest.raises(ValueError):
        Material.from_scene(0.2, "plane_strain", "c_s", 100.0, 0.0, "diagonal")


def test_velocity_unit_c_r_scales_the_block_against_the_interface():
    """c_r = 1 (the default): the block's k_n, k_t grow by (c_s/c_r)^2 = 1.2050 against c_s = 1, while k_x,
    k_y, F_N and the substrate stay."""
    cs = derive(scene(**{"material.velocity_unit": "c_s"})).material
    cr = derive(scene(**{"material.velocity_unit": "c_r"})).material
    assert cr.c_r == pytest.approx(1.0, abs=1e-12)
    assert cr.kn_top / cs.kn_top == pytest.approx(1 / 0.910996 ** 2, rel=1e-5)
    assert cr.kn_bottom == cs.kn_bottom == 100.0


@pytest.mark.parametrize("key, value", [("drive.hold", "y"), ("interface.rebond", "closest"),
                                        ("interface.rebond_within", -0.1), ("material.kn_spring", "normal")])
def test_bad_reading_values_are_refused(key, value):
    with pytest.raises(ConfigError, match=key.replace(".", r"\.")):
        scene(**{key: value})


def test_shipped_defaults_are_the_chosen_reading():
    """The reading `parslip paper --readings` chose (docs/model/readings.md): c_r as the velocity unit and a
    re-formed bond's rest offset 0; the other readings keep the old behaviour."""
    sc = scene()
    assert sc["material.velocity_unit"] == "c_r" and sc["interface.reform_x0"] == "zero"
    assert (sc["material.kn_spring"], sc["drive.hold"], sc["interface.rebond"], sc["interface.rebond_within"],
            sc["material.bottom_kn"], sc["load.FN"], sc["lattice.bottom_cols"], sc["material.model"]) == \
        ("along", "x", "nearest", 0.0, 100.0, 1.0, 300, "plane_strain")
