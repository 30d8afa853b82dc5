"""Study 5 of docs/studies/weakening.md (``parslip.studies.weakening.precursors``) and the arrest prediction with
the law's Gamma (``analysis.arrest.arrest_prediction(..., gamma=)``).

- The fit is one line per normal load through every loading height (Katano et al. 2014, Fig. 2): drawn
  precursors on two lines, three heights each, give back both lines exactly, which a fit per height or a pooled
  fit would not.
- The prediction on a drawn record (a step of prestress ahead of the rear edge, the residual behind the arrest)
  with Gamma given is the root of G(L) = Gamma that scipy's quadrature of the edge crack's singular form finds
  (``test_arrest._k_quad``), to a site, in the run's units (tractions in rho c_r^2, Gamma in m c_r^2 / a).
- The reflection time is 2 H / c_l of the shorter block.
"""
import math
from types import SimpleNamespace

import numpy as np
import pytest
from scipy import optimize
from test_arrest import _k_quad

from parslip.analysis import arrest
from parslip.analysis.cracks import _material, mode2_compliance
from parslip.analysis.results import Run
from parslip.model.physics import DENSITY, ROW_HEIGHT
from parslip.scene.schema import SCHEMA
from parslip.studies.weakening import precursors as wp


def _drawn(lines):
    rows = []
    for fn, slope, icpt in lines:
        for h, mus in (("low", (0.2, 0.5)), ("mid", (0.3, 0.6)), ("high", (0.4, 0.7))):
            rows += [{"F_N": fn, "block_rows": 100, "height": h, "mu_arrest": mu,
                      "length_over_lambda": slope * mu + icpt} for mu in mus]
    return rows


def test_one_line_per_normal_load_through_every_height():
    rows = _drawn(((10.0, 20.0, -1.0), (40.0, 5.0, 2.0)))
    fit = wp.load_fits(rows)
    assert sorted(fit) == [(10.0, 100), (40.0, 100)]
    for fn, slope, icpt in ((10.0, 20.0, -1.0), (40.0, 5.0, 2.0)):
        fn = (fn, 100)
        assert fit[fn]["slope"] == pytest.approx(slope) and fit[fn]["intercept"] == pytest.approx(icpt)
        assert fit[fn]["r2"] == pytest.approx(1.0) and fit[fn]["n_fit"] == 6
    pooled = wp.line_fit([a["mu_arrest"] for a in rows], [a["length_over_lambda"] for a in rows])
    assert pooled["r2"] < 0.8


def _record(before, after, n):
    scene = {k: SCHEMA[k].default for k in ("material.nu", "material.model", "material.velocity_unit",
                                            "material.bottom_kn", "material.bottom_kt", "material.kn_spring")}
    c_r = _material(SimpleNamespace(scene=scene)).c_r
    iface = {"t": np.array([0.0, 1.0, 2.0]), "x": (np.arange(n) + 0.5) / n,
             "sxy": np.array([before, before, after], float)}
    return Run.from_arrays(iface, scene, {"c_r": c_r}), c_r


def test_the_prediction_with_the_laws_gamma_is_the_independent_root():
    n, b, dtau, tau_r = 400, 60, 0.05, 0.02                 # rho c_r^2; the drop dtau on [0, b), -tau_r beyond
    before = np.r_[np.full(b, dtau + tau_r), np.zeros(n - b)]
    run, c_r = _record(before, np.full(n, tau_r), n)
    m = _material(run)
    H0, scale = mode2_compliance(0.0, m.kn_top, m.kt_top), DENSITY * c_r ** 2
    g_of = lambda L: 0.5 * H0 * (scale * _k_quad(b, dtau, tau_r, L)) ** 2 / c_r ** 2   # m c_r^2 / a
    gamma = 0.5 * g_of(b)                                   # reached inside the drop: it runs past b and stops
    L_zero = optimize.brentq(lambda L: _k_quad(b, dtau, tau_r, L), b, 20 * b)
    L_root = optimize.brentq(lambda L: g_of(L) - gamma, b, L_zero)
    front = SimpleNamespace(direction=1)
    pre = SimpleNamespace(nucleation_time=0.5, nucleation_x=0.5 / n, arrest_time=1.5, arrest_length=100 / n,
                          front=front)
    got = arrest.arrest_prediction(run, pre, gamma=gamma)
    assert got["geometry"] == "edge" and got["Gamma"] == gamma
    assert got["tau_r"] == pytest.approx(tau_r)
    assert got["L_predicted"] == pytest.approx(L_root, abs=1.0)
    assert got["G_at_arrest_over_Gamma"] == pytest.approx(g_of(100) / gamma, rel=2e-2)   # near K = 0: cancellation


def test_the_reflection_time_is_the_p_waves_round_trip_through_the_shorter_block():
    scene = {"lattice.top_rows": 120, "lattice.bottom_rows": 100, "lattice.top_cols": 500}
    run = Run.from_arrays({"t": np.zeros(1), "x": np.zeros(1)}, scene, {"c_r": 1.0, "c_s": 1.1, "c_l": 1.8})
    assert wp.reflection_time(run) == pytest.approx(2 * 100 * ROW_HEIGHT / 1.8 / 500)
    assert math.isclose(wp.reflection_time(run) * 500, 96.225, rel_tol=1e-4)


def test_bursts_split_where_the_breaks_pause_longer_than_the_gap():
    t = np.array([0.0, 0.1, 0.2, 1.0, 1.05, 3.0])
    got = arrest.break_bursts(t, np.zeros(6, int), 0.5)
    assert [list(b) for b in got] == [[0, 1, 2], [3, 4], [5]]
    assert arrest.break_bursts(np.zeros(0), np.zeros(0, int), 0.5) == []


def test_edge_cracks_keep_a_crack_whole_through_the_sites_still_broken():
    """Drawn breaks on 200 sites: a crack from the pushed edge breaks sites 0-39, pauses, then a second one runs
    through sites 0-19 (still broken: no breaks there) and breaks 20-79 and, after a stretch of 20 sites it
    runs through without a break (quicker than the gap), 100-119; a 3-break burst; then one that crosses to the
    far edge; a break during the settle (t < 0) is left out."""
    n = 200
    seg = lambda lo, hi, t0, v: (t0 + (np.arange(lo, hi) - lo) / (v * n), np.arange(lo, hi))
    parts = [(np.array([-0.5]), np.array([7])), seg(0, 40, 1.0, 0.5), seg(20, 80, 3.0, 0.5),
             seg(100, 120, 3.0 + 80 / (0.5 * n), 0.5), (np.array([5.0, 5.01, 5.02]), np.array([3, 4, 5])),
             seg(0, n, 7.0, 0.5)]
    t = np.concatenate([p[0] for p in parts])
    site = np.concatenate([p[1] for p in parts])
    events = {"time": t, "site": site, "kind": np.ones(len(t), int)}
    run = Run.from_arrays({"t": np.array([0.0]), "x": (np.arange(n) + 0.5) / n, "events": events})
    got = arrest.edge_cracks(run, gap=0.25, min_breaks=10)
    assert [c.arrested for c in got] == [True, True, False]
    a, b, c = got
    assert a.arrest_length * n == 40 and a.breaks == 40 and a.span == 40 and a.first_x == pytest.approx(0.5 / n)
    assert b.arrest_length * n == 120 and b.breaks == 80 and b.span == 100 and b.first_x == pytest.approx(20.5 / n)
    assert b.nucleation_x == pytest.approx(0.5 / n) and b.front.direction == 1
    assert b.arrest_time == pytest.approx(3.0 + 80 / (0.5 * n) + 19 / (0.5 * n))
    back = arrest.edge_cracks(run, gap=0.25, min_breaks=10, direction=-1)    # seen from the other edge
    assert back[0].arrest_length * n == 200 and not back[0].arrested
    assert back[0].nucleation_x == pytest.approx(1 - 0.5 / n)
