"""Study 2 of docs/studies/weakening.md, the law's shape (``parslip.studies.weakening.shape``): its sweep holds
tau_p and Gamma while it trades the elastic share against D_c, and the study's measures (the elastic share,
D_c,eff, Uenishi & Rice's nucleation length, the scaled Andrews distance, the reflected wave's return) agree
with the law's closed form and with the measures of study 1 they stand beside."""
import math
import os

import numpy as np
import pytest

from parslip.analysis import lefm
from parslip.analysis.rupture import law_scales
from parslip.scene.derive import derive
from parslip.scene.load import load
from parslip.studies import sweep as S
from parslip.studies.weakening import shape

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# The study's sweeps and the elastic shares of their points, in order.
SHARES = {"weakening_shape.toml": (0.125, 0.25, 0.4991, 0.75, 1.0), "weakening_shape_normal.toml": (0.125, 0.25),
          "weakening_shape_zone.toml": (0.125, 1.0)}


def _scenes():
    """Each point of the study's sweeps, resolved (the base scene under the point's overrides), with its
    sweep's file name."""
    cwd = os.getcwd()
    os.chdir(ROOT)                                 # the sweep's base is relative to the checkout
    try:
        out = []
        for name in SHARES:
            sw = S.load_sweep(os.path.join(ROOT, "run", "studies", name))
            out += [(name, load(sw.base, sets=dict(p.sets))) for p in sw.points]
        return out
    finally:
        os.chdir(cwd)


@pytest.fixture(scope="module")
def swept():
    return [(name, sc, law_scales(derive(sc))) for name, sc in _scenes()]


def test_the_sweeps_hold_tau_p_gamma_lc_and_lambda_and_vary_the_share(swept):
    """tau_p, Gamma (so D_c,eff, L_c, Lambda) within 0.2 % on every point of both sweeps; the shares each
    names; L_c and Lambda at least 5 sites; S the same."""
    sc = [s for _, _, s in swept]
    for key in ("tau_p", "Gamma", "L_c", "Lambda", "S"):
        v = np.array([s[key] for s in sc])
        assert np.ptp(v) <= 2e-3 * abs(v.mean()), (key, v)
    assert min(min(s["L_c"], s["Lambda"]) for s in sc) >= 5.0
    for name, shares in SHARES.items():
        got = [shape.elastic_share(s) for n, _, s in swept if n == name]
        assert np.allclose(got, shares, atol=1e-3), (name, got)
    assert np.allclose([shape.effective_dc(s) for s in sc], 0.99826, rtol=2e-3)


def test_the_share_is_the_laws_closed_form(swept):
    """s = x_b / (x_b + D_c) at tau_r = 0, x_b = sqrt(delta_b^2 - y^2), y = delta0 - (F_N / N) / k_y, from the
    scene's numbers alone (not through ``law_scales``; y at the scene's k_y); the edges peak at least 2.2 times
    the contact's x_b, with delta_b at least study 1's 1.2 a."""
    for _, scene, sc in swept:
        y = scene["interface.delta0"] - scene["load.FN"] / scene["lattice.top_cols"] / scene["interface.ky"]
        xb = math.sqrt(scene["interface.delta_b"] ** 2 - y ** 2)
        assert shape.elastic_share(sc) == pytest.approx(xb / (xb + scene["interface.softening"]), rel=1e-9)
        for patch in scene["interface.patch"]:
            assert math.sqrt(patch["delta_b"] ** 2 - y ** 2) >= 2.2 * xb * (1 - 2e-3)
            assert patch["delta_b"] >= 1.2


def test_a_law_with_a_residual_shares_gamma_as_its_areas():
    """With tau_r > 0: Gamma = tau_p x_b / 2 + (tau_p - tau_r) D_c / 2, so D_c,eff = 2 Gamma / (tau_p - tau_r)
    and s = (tau_p x_b / 2) / Gamma."""
    sc = {"tau_p": 2.0, "tau_r": 0.5, "x_b": 0.3, "D_c": 0.8}
    gamma = 2.0 * 0.3 / 2 + 1.5 * 0.8 / 2
    assert shape.effective_dc(sc) == pytest.approx(2 * gamma / 1.5)
    assert shape.elastic_share(sc) == pytest.approx(2.0 * 0.3 / 2 / gamma)


def test_the_nucleation_length_through_lambda_is_uenishi_and_rice_in_the_law_own_units(swept):
    """1.158 M D_c / (tau_p - tau_r) with M and the bond's peak force per a in the engine's units (from the
    law itself, ``InterfaceLaw.strength``) equals the unit-free route through Lambda."""
    for _, scene, sc in swept:
        st = derive(scene)
        v = st.law.strength(st.lattice.n_top_sites, scene["load.FN"])
        mid = len(v["tau_p"]) // 2
        direct = shape.UENISHI_RICE * sc["M"] * v["D_c"][mid] / (v["tau_p"][mid] - v["tau_r"][mid])
        assert shape.nucleation_length(sc["Lambda"], sc["D_c"], shape.effective_dc(sc)) == \
            pytest.approx(direct, rel=1e-6)


def test_the_scaled_distance_is_andrews_at_share_zero_and_vanishes_at_one():
    assert shape.dunham_length(0.8, 9.75, 0.0) == pytest.approx(float(lefm.andrews_f(0.8)) * 9.75)
    assert shape.dunham_length(0.8, 9.75, 1.0) == 0.0
    assert shape.dunham_length(0.8, 9.75, 0.25) == pytest.approx(0.75 * shape.dunham_length(0.8, 9.75, 0.0))


def test_the_reflected_wave_meets_a_tip_at_c_r_at_study_1s_reflection_distance():
    """A tip at c_r (= 1) from the hypocentre meets the wave reflected from h away where D / 1 = sqrt(D^2 +
    4 h^2) / c_l, at D = 2 h / sqrt(c_l^2 - 1): the distance study 1 calls ``reflection``."""
    h, c_l = 186.2, 1.79254
    D = 2 * h / math.sqrt(c_l ** 2 - 1)
    assert shape.reflection_time(D, h, c_l) == pytest.approx(D)
    assert shape.reflection_time(0.0, h, c_l) == pytest.approx(2 * h / c_l)
    assert shape.reflection_time(D / 2, h, c_l) > D / 2        # a tip at c_r gets there before the wave
